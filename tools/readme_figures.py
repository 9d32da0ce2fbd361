"""Make the README's pictures: the demo composite, the cutout under four contrasting lights, every preset, a
horse under the sun and a softbox (its legs in the sun's shadow), a low sun's long shadow on a wide canvas, and a
ball lifted and a board made flat or deep (--lift, --thickness).

Run: python tools/readme_figures.py [--out docs/img]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw
from skimage import data

from ssn_engine.compositing import composite_shadow, over
from ssn_engine.cli import DEMO_PRESET
from ssn_engine.host_kit.light_map import PRESETS, SUN, GaussianLight, LightMap, preset
from ssn_engine.host_kit.light_map_picture import map_rgb
from ssn_engine.methods import ShadowMethod, load_method
from ssn_engine.samples import pawn_cutout, studio_background
from ssn_engine.session import ShadowSession

TILE = 360
CONTRAST = ("low-sun-left", "low-sun-right", "high-sun", "softbox")  # the README's "shadow follows the light" row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--out", default="docs/img")
    out = Path(parser.parse_args().out)
    out.mkdir(parents=True, exist_ok=True)
    cutout, background = pawn_cutout(), studio_background()
    loaded = load_method("auto")
    session = ShadowSession(cutout[..., 3], loaded.method)
    h, w = cutout.shape[:2]
    tiles = {}
    for name in PRESETS:
        light = preset(name)
        shadow = session.render(light).full_canvas(w, h)
        image = over(composite_shadow(background, shadow, opacity=0.85), cutout)
        if name == DEMO_PRESET:
            Image.fromarray(image).save(out / "demo.png", optimize=True)
        tile = Image.fromarray(image).crop((150, 150, 1050, 900)).resize((TILE, TILE * 750 // 900))
        sky = Image.frombytes("RGB", (128, 64), map_rgb(light, 128, 64))  # the sky map as the plug-ins draw it
        tile.paste(sky, (TILE - 128 - 6, 6))
        ImageDraw.Draw(tile).text((8, 6), name, fill=(20, 20, 20))
        tiles[name] = tile
    sheet(list(tiles.values()), out / "presets.png")
    sheet([tiles[name] for name in CONTRAST], out / "follow_the_light.png")
    long_shadows(cutout, loaded.method).save(out / "long_shadow.png", optimize=True)
    hard_light(loaded.method).save(out / "hard_light.png", optimize=True)
    lift_and_thickness(loaded.method).save(out / "lift_thickness.png", optimize=True)
    print(
        f"wrote demo.png, presets.png, follow_the_light.png, hard_light.png, long_shadow.png and lift_thickness.png "
        f"in {out} with the {loaded.method.name} method"
    )


def long_shadows(cutout: np.ndarray, method: ShadowMethod, elevation: float = 8.0) -> Image.Image:
    """The cutout in the middle of a canvas three times as wide under a sun ``elevation`` degrees up on the
    left, then on the right: shadows several heights long, continued past the network's frame."""
    h, w = cutout.shape[:2]
    canvas = np.zeros((h, 3 * w, 4), np.uint8)
    canvas[:, w : 2 * w] = cutout
    background = studio_background((3 * w, h))
    session = ShadowSession(canvas[..., 3], method)
    rows = []
    for u, side in ((0.25, "left"), (0.75, "right")):
        light = LightMap([GaussianLight.disk(u, 1.0 - elevation / 90.0, SUN)])
        shadow = session.render(light).full_canvas(3 * w, h)
        row = Image.fromarray(over(composite_shadow(background, shadow, opacity=0.85), canvas)).crop((0, 150, 3 * w, h))
        row = row.resize((row.width * 2 // 5, row.height * 2 // 5))
        ImageDraw.Draw(row).text((8, 6), f"sun {elevation:g} degrees up, {side}", fill=(20, 20, 20))
        rows.append(row)
    page = Image.new("RGB", (rows[0].width, sum(r.height for r in rows)))
    for i, row in enumerate(rows):
        page.paste(row, (0, i * row.height))
    return page


def hard_light(method: ShadowMethod, horizon: float = 100.0, fov: float = 40.0) -> Image.Image:
    """scikit-image's horse standing on a white ground under the four contrasting lights (a 0.53-degree sun low
    on the left and on the right, high, and a 16-degree softbox), each with its sky map; seen from a little above
    (the horizon at canvas row ``horizon``, ``fov`` degrees), as a photograph taken standing would."""
    horse = ~data.horse()  # True on the horse
    h, w = 1000, 1500
    alpha = np.zeros((h, w), np.uint8)
    y0, x0 = 420, (w - horse.shape[1]) // 2
    alpha[y0 : y0 + horse.shape[0], x0 : x0 + horse.shape[1]] = horse * 255
    cutout = np.dstack([np.full((h, w, 3), 90, np.uint8), alpha])
    background = np.full((h, w, 3), 235, np.uint8)
    session = ShadowSession(alpha, method, horizon, fov)
    tiles = []
    for name in CONTRAST:
        light = preset(name)
        shadow = session.render(light).full_canvas(w, h)
        tile = Image.fromarray(over(composite_shadow(background, shadow, opacity=0.85), cutout)).crop((0, 250, w, h))
        tile = tile.resize((TILE * 2, tile.height * TILE * 2 // w))
        sky = Image.frombytes("RGB", (128, 64), map_rgb(light, 128, 64))
        tile.paste(sky, (tile.width - 128 - 6, 6))
        ImageDraw.Draw(tile).text((8, 6), name, fill=(20, 20, 20))
        tiles.append(tile)
    page = Image.new("RGB", (2 * tiles[0].width, 2 * tiles[0].height), (255, 255, 255))
    for i, tile in enumerate(tiles):
        page.paste(tile, ((i % 2) * tile.width, (i // 2) * tile.height))
    return page


def lift_and_thickness(method: ShadowMethod, horizon: float = 150.0, fov: float = 40.0) -> Image.Image:
    """The artist's geometry (``--lift``, ``--thickness``): a ball resting, lifted by a quarter of its height and
    by half of it, under a high and a low 0.53-degree sun (two rows); then a board read as it is, as a flat sign
    (thickness 0) and as a deep box (thickness 2) under a sun from the side (a third row)."""
    w, h = 900, 560
    yy, xx = np.mgrid[0:h, 0:w]
    ball = ((((xx + 0.5 - 400) ** 2 + (yy + 0.5 - 300) ** 2) < 70**2) * 255).astype(np.uint8)
    board = np.zeros((h, w), np.uint8)
    board[190:370, 340:460] = 255
    suns = {
        "high sun": LightMap([GaussianLight.disk(0.42, 0.3, SUN)]),
        "low sun": LightMap([GaussianLight.disk(0.3, 0.75, SUN)]),
    }
    cases = [(ball, name, light, lift, None) for name, light in suns.items() for lift in (0.0, 35.0, 70.0)]
    side = LightMap([GaussianLight.disk(0.2, 0.55, SUN)])
    cases += [(board, "sun from the side", side, 0.0, t) for t in (None, 0.0, 2.0)]
    tiles = []
    for alpha, name, light, lift, thickness in cases:
        session = ShadowSession(alpha, method, horizon, fov)
        session.set_geometry(lift, thickness)
        shadow = session.render(light).full_canvas(w, h)
        cutout = np.dstack([np.full((h, w, 3), 90, np.uint8), alpha])
        tile = Image.fromarray(over(composite_shadow(np.full((h, w, 3), 235, np.uint8), shadow), cutout))
        tile = tile.crop((150, 170, w - 50, h)).resize((TILE, TILE * (h - 170) // (w - 200)))
        shape = "read" if thickness is None else f"{thickness:g}"
        caption = f"{name}, lift {lift:g}" if alpha is ball else f"{name}, thickness {shape}"
        ImageDraw.Draw(tile).text((8, 6), caption, fill=(20, 20, 20))
        tiles.append(tile)
    page = Image.new("RGB", (3 * TILE, 3 * tiles[0].height), (255, 255, 255))
    for i, tile in enumerate(tiles):
        page.paste(tile, ((i % 3) * TILE, (i // 3) * tile.height))
    return page


def sheet(tiles: list[Image.Image], path: Path, cols: int = 4) -> None:
    """Tiles in rows of ``cols``, saved as one PNG."""
    rows = -(-len(tiles) // cols)
    page = Image.new("RGB", (cols * TILE, rows * tiles[0].height), (255, 255, 255))
    for i, tile in enumerate(tiles):
        page.paste(tile, ((i % cols) * TILE, (i // cols) * tile.height))
    page.save(path, optimize=True)


if __name__ == "__main__":
    main()
