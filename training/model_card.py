"""The model card (MODEL_CARD.md) written beside model.json: what the graphs are, how they were trained, on which
data, the command that reproduces them and the meshes' attribution."""

from __future__ import annotations

from pathlib import Path

from ssn_engine.model_config import ModelConfig

from .checkpoint import load_models
from .data.store import ViewStore

__all__ = ["MIX_RECORD", "mesh_attribution", "model_card", "put_section", "training_summary"]

MIX_RECORD = "the family mixture"  # model.json "lights" of an SR trained with --lights mix


def mesh_attribution(data: str) -> list[dict]:
    """Licence and attribution of every mesh in the dataset's train and val splits."""
    if not Path(data, "dataset.json").is_file():
        return []
    store = ViewStore(data)
    rows = []
    for m in store.meshes:
        mesh = m["mesh"]
        p = mesh.get("params", {})
        if mesh["split"] in ("train", "val"):
            rows.append(
                {
                    "id": mesh["id"],
                    "split": mesh["split"],
                    "licence": p.get("licence", "generated"),
                    "attribution": p.get("attribution", "procedural / project-generated"),
                    "source": p.get("source_repo", mesh.get("source", "")),
                }
            )
    return rows


def model_card(config: ModelConfig, attribution: list[dict], command: str) -> str:
    """The model card (markdown) shipped next to model.json: ``config`` with its export record, the meshes'
    ``attribution`` (:func:`mesh_attribution`) and the reproducing ``command``."""
    card = config.to_dict()
    ex = card["export"]
    lines = [
        "# SSN shadow model (AOP + SR)",
        "",
        "The paper's Soft Shadow Network (Sheng et al., CVPR 2021) as two ONNX graphs for "
        "`ssn_engine.methods.onnx_ssn`: AOP (mask -> AO map A^(1/3)) and SR (mask, AO, 16 x 32 ELM -> shadow s,",
        "the conventions' normalised inverse shadow).",
        "",
        f"- Resolution R = {card['resolution']} (the engine resamples its 256 x 256 frames to R and back).",
    ]
    for m in ("aop", "sr", "aop_camera"):
        if m not in ex:
            continue
        r = ex[m]
        rebuilt = r.get("rebuilt_from") or [None] * len(r["checkpoints"])
        runs = " and ".join(
            f"U-Net widths {w}, " + (f"the network of `{g}` (`{p}`)" if g else f"{st} steps ({n} samples, `{p}`)")
            for p, w, st, n, g in zip(r["checkpoints"], r["widths"], r["steps"], r["samples"], rebuilt, strict=True)
        )
        mean = f"the mean of {len(r['checkpoints'])} networks, " if len(r["checkpoints"]) > 1 else ""
        reused = ""
        if r.get("reused_from"):
            how = "without its mirror average" if r.get("mirror_average") is False else "as it is"
            reused = f" (the graph of `{r['reused_from']}`, reused {how})"
        label, camera = m.upper(), ""
        if m == "aop_camera":
            label = "AOP with camera"
            camera = " (for calls that give the camera input: it also takes the horizon row and focal length)"
        lines.append(
            f"- {label}: {mean}{runs}{reused}{camera}, {r['weights']} weights, "
            f"{r['bytes'] / 1e6:.2f} MB, max abs diff to torch {r['max_abs_diff']:.1e}"
        )
    if card.get("card_input"):
        lines.append(
            "- Geometry-guided SR: it also takes the engine's geometric card shadow for the same light map "
            "(since v3.9 a texel holding 5 % of the light casts the mean shadow over its area; traced with the "
            "camera input when given, else the model's camera estimator's reading of the mask, or without one the "
            "conventions' default camera) and outputs a "
            "correction of it, so the shadow's direction and length come from the card's geometry and the "
            f"network refines contact, softness and shape. Light maps in training: {card['lights']}."
        )
    if card.get("output_floor"):
        lines.append(
            f"- Output floor {card['output_floor']}: the engine maps s to (s - floor) / (1 - floor), clipped "
            "(removes the network's faint noise; chosen on the validation split, docs/benchmark.md)."
        )
    if "output_floor_small_lights" in card:
        lines.append(
            f"- Output floor {card['output_floor_small_lights']} for one or two small lights, blended in as the "
            "light map's energy concentrates in its 16 brightest texels (a hard shadow has no faint tails, so "
            "faint values there are haze; onnx_ssn.floor_for; chosen on the validation split, docs/training.md)."
        )
    if card.get("shadow_reach"):
        lines.append(
            f"- Shadow reach {card['shadow_reach']} pixels (N = 256): for one or two small lights the engine keeps "
            "the network's shadow within that distance of the card's shadow and of the cutout and fades it out "
            "beyond, where no occluder can cast and what the network leaves is haze (onnx_ssn.reach_weights; "
            "chosen on the validation split, docs/training.md)."
        )
    if card.get("ao_gamma", 1.0) != 1.0:
        lines.append(
            f"- AO gamma {card['ao_gamma']}: the engine uses the predicted AO map raised to this power, lighter "
            "where the AOP darkens objects more than their true AO; the SR gains on every light family "
            "(chosen on the validation split, docs/training.md)."
        )
    if card.get("card_blur"):
        lines.append(
            f"- Card blur {card['card_blur']} pixels (R): the engine blurs the card's shadow by a Gaussian of this "
            "size before the SR sees it; the card's aliased steps at a wedge's tip made the SR leave speckles "
            "(onnx_ssn.blur_frames; checked on the validation split, docs/training.md)."
        )
    if card.get("mirror_average"):
        # a reused AOP keeps its own mirror average or none (as the shipped one), as does --aop-camera's
        which = (
            "the SR graph" if ex["aop"].get("reused_from") or ex["aop"].get("mirror_average") is False else "each graph"
        )
        lines.append(
            f"- Mirror average: {which} runs its network on the input and on its mirror image (frames in x, the "
            "ELM in azimuth) and averages the two (training.model.MirrorAverage)."
        )
    if card.get("sr_training"):
        lines.append(f"- SR training: {card['sr_training']}.")
    t = ex["timing"]
    lines += [
        f"- SR latency (onnxruntime, median, 2-core CPU): {t['sr_at_R_ms']:.1f} ms at R, "
        f"{t['sr_engine_256_ms']:.1f} ms for a 256 frame including resampling.",
        "",
        "## Training data",
        "",
        f"Shadow bases of `{card.get('training_data')}` (training/data, `python -m training.make_dataset`), "
        "train split; soft shadows from random light maps on the fly (Table 1, or the mixture of light families "
        "of `training.elm`), exact linear algebra on the bases.",
        "",
    ]
    lines += [
        "## Reproduce",
        "",
        "Every stage that made this model, from the meshes to a model folder, in order (docs/training.md says why "
        "each stage is as it is):",
        "",
        "```",
        command,
        "```",
        "",
        "## Mesh attribution",
        "",
        "The training meshes are CC BY (attribution below), CC0 or public domain. Per mesh:",
        "",
        "| mesh | licence | attribution | source |",
        "|---|---|---|---|",
    ]
    lines += [f"| {a['id']} | {a['licence']} | {a['attribution']} | {a['source']} |" for a in attribution]
    return "\n".join(lines) + "\n"


def training_summary(path: Path, ck: dict) -> str:
    """How long a checkpoint trained (from its run's log.csv), following ``--init-from`` back to the run it was
    fine-tuned from (a checkpoint rebuilt from a graph, :mod:`training.onnx_weights`, carries its record)."""
    if "rebuilt_from" in ck:
        return ck.get("training") or f"the network of {ck['rebuilt_from']}"
    log = path.with_name("log.csv")
    rows = log.read_text().splitlines()[1:] if log.is_file() else []
    minutes = f"{float(rows[-1].split(',')[5]) / 60:.0f} min of training time, " if rows else ""
    args = ck.get("args") or {}
    loss = f" (loss: L2 + {args['zncc_weight']:g} x (1 - ZNCC))" if args.get("zncc_weight") else ""
    text = f"{minutes}{ck['step']} steps, {ck['samples']} samples{loss}"
    parent = args.get("init_from")
    if parent and Path(parent).is_file():
        text = (
            f"{training_summary(Path(parent), load_models([parent])[1][0])}, then fine-tuned for {text} "
            f"(learning rate {args['lr']:g})"
        )
    return text


def put_section(card: Path, title: str, section: str) -> None:
    """Write ``section`` (starting with the heading ``title``) into the model card at ``card``: in place of the
    section of that title, else before "## Training data"."""
    text = card.read_text()
    if title in text:
        start = text.index(title)
        text = text[:start] + section + text[text.index("## ", start + len(title)) :]
    else:
        at = text.index("## Training data")
        text = text[:at] + section + text[at:]
    card.write_text(text)
