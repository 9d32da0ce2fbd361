"""Make the README's pictures: the demo composite, the cutout under four contrasting lights, every preset.

Run: python tools/readme_figures.py [--out docs/img]
"""

from __future__ import annotations

import argparse
from pathlib import Path

from PIL import Image, ImageDraw

from ssn_engine.compositing import composite_shadow, over
from ssn_engine.cli import DEMO_PRESET
from ssn_engine.light_map import PRESETS, preset
from ssn_engine.light_map_picture import map_rgb
from ssn_engine.methods import load_method
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
    print(f"wrote demo.png, presets.png and follow_the_light.png in {out} with the {loaded.method.name} method")


def sheet(tiles: list[Image.Image], path: Path, cols: int = 4) -> None:
    """Tiles in rows of ``cols``, saved as one PNG."""
    rows = -(-len(tiles) // cols)
    page = Image.new("RGB", (cols * TILE, rows * tiles[0].height), (255, 255, 255))
    for i, tile in enumerate(tiles):
        page.paste(tile, ((i % cols) * TILE, (i // cols) * tile.height))
    page.save(path, optimize=True)


if __name__ == "__main__":
    main()
