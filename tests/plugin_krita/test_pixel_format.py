import struct

import pytest

from plugin_krita.ssn_shadow.adapters.pixel_format import (
    UnsupportedFormat,
    clip_rect,
    extract_alpha,
    pixel_format,
    place_rows,
    rect_difference,
    shadow_color,
)


@pytest.mark.parametrize(
    "depth, dtype, channels, size",
    [
        ("U8", "uint8", "bgra", 4),
        ("U16", "uint16", "bgra", 8),
        ("F16", "float16", "rgba", 8),
        ("F32", "float32", "rgba", 16),
    ],
)
def test_depths(depth, dtype, channels, size):
    fmt = pixel_format("RGBA", depth)
    assert (fmt.dtype, fmt.channels, fmt.pixel_size) == (dtype, channels, size)
    assert fmt.render_format() == {"dtype": dtype, "channels": channels}


@pytest.mark.parametrize("model, depth", [("CMYKA", "U8"), ("GRAYA", "U16"), ("LABA", "U16"), ("RGBA", "F64")])
def test_other_models_get_a_clear_message(model, depth):
    with pytest.raises(UnsupportedFormat, match="Convert Image Color Space"):
        pixel_format(model, depth)


def test_extract_alpha_every_depth():
    assert extract_alpha(bytes([1, 2, 3, 4, 5, 6, 7, 8]), pixel_format("RGBA", "U8")) == bytes([4, 8])
    u16 = struct.pack("<8H", 1, 2, 3, 65535, 5, 6, 7, 300)
    assert struct.unpack("<2H", extract_alpha(u16, pixel_format("RGBA", "U16"))) == (65535, 300)
    f16 = struct.pack("<8e", 0.1, 0.2, 0.3, 0.5, 0, 0, 0, 1.0)
    assert struct.unpack("<2e", extract_alpha(f16, pixel_format("RGBA", "F16"))) == (0.5, 1.0)
    f32 = struct.pack("<8f", 0.1, 0.2, 0.3, 0.25, 0, 0, 0, 0.75)
    assert struct.unpack("<2f", extract_alpha(f32, pixel_format("RGBA", "F32"))) == (0.25, 0.75)
    with pytest.raises(ValueError):
        extract_alpha(b"\x00" * 5, pixel_format("RGBA", "U8"))


def test_place_rows_and_clip():
    plane = place_rows(bytes([1, 2, 3, 4]), 1, 1, 2, 2, 4, 3, 1)
    assert bytes(plane) == bytes([0, 0, 0, 0, 0, 1, 2, 0, 0, 3, 4, 0])
    full = place_rows(bytes(range(8)), 0, 1, 4, 2, 4, 3, 1)
    assert bytes(full[4:]) == bytes(range(8))
    assert clip_rect(-5, -5, 10, 10, 4, 3) == (0, 0, 4, 3)
    assert clip_rect(10, 10, 5, 5, 4, 3)[2:] == (0, 0)


def test_shadow_colour_linearised_for_linear_profiles():
    assert shadow_color((0.5, 0, 1), "sRGB-elle-V2-srgbtrc.icc") == [0.5, 0.0, 1.0]
    lin = shadow_color((0.5, 0, 1), "sRGB-elle-V2-g10.icc")
    assert lin[0] == pytest.approx(0.214, abs=1e-3) and lin[1:] == [0.0, 1.0]


@pytest.mark.parametrize("dtype, fmt", [("uint8", "B"), ("uint16", "H"), ("float16", "e"), ("float32", "f")])
def test_opaque_everywhere_in_every_depth(dtype, fmt):
    """Select All or a full-canvas opaque layer is no cutout; one transparent pixel makes it one (every depth:
    a half-float alpha broke this check once, and with it every F16 document)."""
    from plugin_krita.ssn_shadow.adapters.pixel_format import opaque_everywhere

    one = {"uint8": 255, "uint16": 65535}.get(dtype, 1.0)
    opaque = struct.pack(f"<{100}{fmt}", *([one] * 100))
    holed = struct.pack(f"<{100}{fmt}", *([one] * 99 + [0]))
    half_transparent = struct.pack(f"<{100}{fmt}", *([one] * 99 + [one * 0.4 if fmt in "ef" else int(one * 0.4)]))
    assert opaque_everywhere(opaque, dtype)
    assert not opaque_everywhere(holed, dtype) and not opaque_everywhere(half_transparent, dtype)


def _cells(rect):
    x, y, w, h = rect
    return {(i, j) for i in range(x, x + w) for j in range(y, y + h)}


@pytest.mark.parametrize(
    "new",
    [(2, 2, 3, 3), (0, 0, 6, 5), (-3, 1, 5, 2), (4, -2, 9, 3), (7, 7, 2, 2), (1, 1, 0, 4), (-1, -1, 9, 9)],
)
def test_a_rewritten_shadow_clears_only_the_old_pixels_it_does_not_cover(new):
    """The Krita layer writer clears the previous shadow's rect minus the new one (the new pixels overwrite the
    rest): exactly those pixels, each once."""
    old = (0, 0, 6, 5)
    parts = rect_difference(old, new)
    cells = [c for p in parts for c in _cells(p)]
    assert len(cells) == len(set(cells))  # no pixel written twice
    assert set(cells) == _cells(old) - _cells(new)
    assert all(w > 0 and h > 0 for _x, _y, w, h in parts)
