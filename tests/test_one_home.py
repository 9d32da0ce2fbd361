"""Every rule the hosts and the engine share lives in one home, the host kit (``ssn_engine/host_kit``): a module of
the engine or of a plug-in that defines a camera bound, the default field of view, the ELM's shape, the AO strength
op, or (a plug-in) the wording of "no shadow" and of the camera read fails here, and so does a module of the
engine, a plug-in or training that rasterises the sky map outside its home.

The scan reads the source (AST): numbers that are such a rule, written where the rule is used instead of named
from the kit. (Training keeps ranges of its own, the cameras and lights it samples: only its sky map is
checked.)
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from ssn_engine.plugin_files import KIT_PACKAGE

ROOT = Path(__file__).resolve().parents[1]
SCANNED = ("ssn_engine", "plugin_krita", "plugin_gimp")
RASTER_HOMES = {  # the sky map's definition (stdlib) and its numpy form (module docstrings say so)
    ROOT / "ssn_engine" / KIT_PACKAGE / "sky_map.py",
    ROOT / "ssn_engine" / "hemisphere.py",
}
FOV_WORDS = ("fov", "field_of_view")
WORDING = ("no visible shadow", "outline: horizon at row", "has no light", "casts no shadow visible")  # the hosts'
SMALL = 2  # numbers below it (a count of decimals, a step of 1) are no field of view


def _numbers(node: ast.AST) -> list[float]:
    """The numbers written in ``node`` (not an index: ``RANGE[1]`` names its bound), of at least ``SMALL``."""
    skipped = {id(n) for s in ast.walk(node) if isinstance(s, ast.Subscript) for n in ast.walk(s.slice)}
    return [
        n.value
        for n in ast.walk(node)
        if isinstance(n, ast.Constant)
        and isinstance(n.value, (int, float))
        and not isinstance(n.value, bool)
        and abs(n.value) >= SMALL
        and id(n) not in skipped
    ]


def _names_fov(node: ast.AST) -> bool:
    """Whether ``node`` (a target, an attribute chain, a call's function) names a field of view."""
    text = ast.unparse(node).lower()
    return any(word in text for word in FOV_WORDS)


def violations(source: str, path: Path | None = None, host: bool = True) -> list[str]:
    """The shared rules that ``source`` (at ``path``; ``host``: a plug-in's) writes out instead of taking them from
    the kit."""
    tree = ast.parse(source)
    found: list[str] = []

    def say(node: ast.AST, what: str) -> None:
        found.append(f"line {getattr(node, 'lineno', '?')}: {what}: {ast.unparse(node)[:80]}")

    for node in ast.walk(tree):
        if isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if node.value is not None and any(_names_fov(t) for t in targets) and _numbers(node.value):
                say(node, "a field of view's value or bound")
        elif isinstance(node, ast.arguments):
            args = [*node.posonlyargs, *node.args, *node.kwonlyargs]
            defaults = [None] * (len(node.posonlyargs) + len(node.args) - len(node.defaults))
            for arg, default in zip(args, [*defaults, *node.defaults, *node.kw_defaults], strict=True):
                if default is not None and _names_fov(ast.Name(arg.arg)) and _numbers(default):
                    say(default, f"a default field of view for {arg.arg}")
        elif isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            if any(_names_fov(s) for s in sides) and any(_numbers(s) for s in sides if not _names_fov(s)):
                say(node, "a field of view compared with a number")
        elif isinstance(node, ast.Call):
            literal_args = [a for a in [*node.args, *(k.value for k in node.keywords)] if _numbers(a)]
            fov_call = _names_fov(node.func) or any(
                isinstance(a, ast.Constant) and a.value in ("fov", "--fov") for a in node.args
            )
            if fov_call and literal_args:
                say(node, "a field of view's value or bound passed as a number")
            if (
                any(
                    isinstance(n, ast.Name) and n.id == "erf" or isinstance(n, ast.Attribute) and n.attr == "erf"
                    for n in ast.walk(node.func)
                )
                and path not in RASTER_HOMES
            ):
                say(node, "the sky map rasterised (erf texel means) outside its home")
        elif isinstance(node, ast.Tuple):
            values = [e.value if isinstance(e, ast.Constant) else None for e in node.elts]
            if any(values[i : i + 2] == [16, 32] for i in range(len(values) - 1)):
                say(node, "the ELM's shape")
        elif isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and abs(node.value) == 100000:
            say(node, "the editors' horizon bound")
        elif isinstance(node, ast.Dict):
            pairs = {
                k.value: v.value
                for k, v in zip(node.keys, node.values, strict=True)
                if isinstance(k, ast.Constant) and isinstance(v, ast.Constant)
            }
            if pairs.get("op") == "strength":
                say(node, "the AO strength op")
    for node in ast.walk(tree):  # user-facing wording, outside docstrings
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            text = node.value.lower()
            if host and any(w in text for w in WORDING) and not _is_docstring(tree, node):
                say(node, "a no-shadow or camera-read sentence")
    return found


def _is_docstring(tree: ast.AST, constant: ast.Constant) -> bool:
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and first.value is constant:
                return True
    return False


def scanned_files(packages: tuple[str, ...] = SCANNED) -> list[Path]:
    """The modules of ``packages`` outside the kit (and an installed copy of it)."""
    return [
        path
        for package in packages
        for path in sorted((ROOT / package).rglob("*.py"))
        if KIT_PACKAGE not in path.relative_to(ROOT).parts
    ]


def test_the_shared_rules_are_defined_only_in_the_host_kit():
    found = {
        str(path.relative_to(ROOT)): v
        for path in scanned_files()
        if (v := violations(path.read_text(encoding="utf-8"), path, host=path.parts[len(ROOT.parts)] != "ssn_engine"))
    }
    found.update(
        (str(path.relative_to(ROOT)), [v for v in violations(path.read_text(encoding="utf-8"), path) if "sky map" in v])
        for path in scanned_files(("training",))
    )
    found = {path: lines for path, lines in found.items() if lines}
    assert not found, "rules the host kit defines, written again:\n" + "\n".join(
        f"{path}: {line}" for path, lines in found.items() for line in lines
    )


@pytest.mark.parametrize(
    "source",
    [
        "DEFAULT_FOV = 45.0",
        "class S:\n    fov: float = 45.0",
        "def f(horizon, fov=45.0): pass",
        "ok = 1.0 <= fov <= 170.0",
        "self.fov.setRange(10.0, 120.0)",
        'ArgSpec("fov", "double", "_Field of view", "blurb", 45.0, 10.0, 120.0)',
        "limits = focal_from_fov(n, 170.0)",
        'p.add_argument("--fov", type=_number_in(1.0, 170.0))',
        "spin.setRange(-100000, 100000)",
        "elm = np.zeros((1, 16, 32))",
        "ey = np.diff(erf(edges / s))",
        "e = [math.erf(x) for x in xs]",
        'edits.append({"op": "strength", "value": 2.0})',
        'status("No visible shadow with these lights.")',
        'text = f"Read from the cutout\'s outline: horizon at row {h}"',
    ],
)
def test_the_scan_finds_a_rule_written_again(source):
    assert violations(source), source


@pytest.mark.parametrize(
    "source",
    [
        "fov = camera_rules.DEFAULT_FOV",
        "self.fov.setRange(*camera_rules.EDITOR_FOV_RANGE)",
        "self.fov.setValue(camera.get('fov', camera_rules.DEFAULT_FOV))",
        "edits.extend(strength_edits(value))",
        "colour = (40, 170, 255)",
        '"""No visible shadow is exactly zero (a docstring)."""',
    ],
)
def test_the_scan_leaves_the_kit_s_names_alone(source):
    assert not violations(source), source
