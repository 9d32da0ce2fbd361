"""The list of shapes a dataset is made from: shared meshes, procedural shapes, anny humans (standing, or in the
poses off their feet), procedural animals, procedural objects with flat parts on the ground.

Every item records how to rebuild its mesh (file, or generator and seed), so
the set is reproducible. Items are ordered by a hash of their id, so any
prefix of the list (and every shard) mixes splits, kinds and sources, and the
order does not change when other items are added.
"""

from __future__ import annotations

from . import meshes
from .grounded import build as build_grounded
from .grounded import grounded_items
from .humans import build as build_human
from .humans import MORE_POSES, human_items
from .items import Item, stable_hash
from .procedural import build as build_procedural
from .procedural import procedural_items
from .quadrupeds import build as build_quadruped
from .quadrupeds import quadruped_items

SOURCES = ("mesh", "procedural", "anny", "anny_poses", "quadruped", "grounded")
# What a set is made of unless told: the sources every set was made of before the people off their feet and the
# animals were added, so that a command made before makes the same set.
DEFAULT_SOURCES = ("mesh", "procedural", "anny")


def manifest_items() -> list[Item]:
    """The shared meshes (split, kind and category from manifest.csv)."""
    out = []
    for row in meshes.read_manifest():
        out.append(
            Item(
                row["id"],
                row["split"],
                row["kind"],
                row["category"],
                "mesh",
                {
                    "file": row["file"],
                    "licence": row["licence"],
                    "attribution": row["attribution"],
                    "source_repo": row["source_repo"],
                    "source_path": row["source_path"],
                },
            )
        )
    return out


def all_items(
    sources: tuple[str, ...] = DEFAULT_SOURCES,
    n_procedural: int = 0,
    n_humans: int = 0,
    seed: int = 0,
    n_quadrupeds: int = 0,
    n_grounded: int = 0,
) -> list[Item]:
    """Items of the chosen sources, ordered by a stable hash of their id."""
    items: list[Item] = []
    if "mesh" in sources:
        items += manifest_items()
    if "procedural" in sources and n_procedural:
        items += procedural_items(n_procedural, seed)
    if "anny" in sources and n_humans:
        items += human_items(n_humans, seed)
    if "anny_poses" in sources and n_humans:
        items += human_items(n_humans, seed, MORE_POSES)
    if "quadruped" in sources and n_quadrupeds:
        items += quadruped_items(n_quadrupeds, seed)
    if "grounded" in sources and n_grounded:
        items += grounded_items(n_grounded, seed)
    return sorted(items, key=lambda it: (stable_hash(it.id), it.id))


def build_mesh(item: Item) -> meshes.Mesh:
    """The item's mesh, cleaned and normalised per the conventions."""
    if item.source == "mesh":
        mesh = meshes.read_ply(meshes.SHARED_MESHES / item.params["file"])
    elif item.source == "procedural":
        mesh = build_procedural(item.params)
    elif item.source in ("anny", "anny_poses"):
        mesh = build_human(item.params)
    elif item.source == "quadruped":
        mesh = build_quadruped(item.params)
    elif item.source == "grounded":
        mesh = build_grounded(item.params)
    else:
        raise ValueError(f"unknown source {item.source!r}")
    return meshes.normalise(meshes.clean(mesh))
