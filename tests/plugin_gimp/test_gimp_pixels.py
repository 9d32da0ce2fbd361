"""Precision -> babl format / protocol dtype mapping, without GIMP."""

import pytest
from ssn_pixels import PixelFormatError, is_blank, layer_image_type, plan_for_precision

COMPONENTS = {
    "u8": ("u8", "uint8", "u8", "uint8"),
    "u16": ("u16", "uint16", "u16", "uint16"),
    "u32": ("float", "float32", "u16", "uint16"),
    "half": ("half", "float16", "u16", "uint16"),
    "float": ("float", "float32", "u16", "uint16"),
    "double": ("float", "float32", "u16", "uint16"),
}


@pytest.mark.parametrize("trc", ["linear", "non-linear", "perceptual"])
@pytest.mark.parametrize("component", list(COMPONENTS))
def test_every_gimp_precision_has_a_plan(component, trc):
    plan = plan_for_precision(f"{component}-{trc}")
    layer_type, layer_dtype, alpha_type, alpha_dtype = COMPONENTS[component]
    assert (plan.layer_type, plan.layer_dtype, plan.alpha_type, plan.alpha_dtype) == (
        layer_type,
        layer_dtype,
        alpha_type,
        alpha_dtype,
    )
    # explicit babl formats: colour in sRGB perceptual encoding, alpha and masks linear, whatever the TRC
    assert plan.shadow_format == f"R'G'B'A {layer_type}"
    assert plan.layer_alpha_format == f"A {alpha_type}"
    assert plan.selection_format == f"Y {alpha_type}"
    assert plan.shadow_nbytes(3, 2) == 3 * 2 * 4 * {"uint8": 1, "uint16": 2, "float16": 2, "float32": 4}[layer_dtype]


@pytest.mark.parametrize("nick", ["u8", "u64-linear", "float-gamma", ""])
def test_unknown_precisions(nick):
    with pytest.raises(PixelFormatError):
        plan_for_precision(nick)


def test_layer_types():
    assert layer_image_type("rgb") == "RGBA_IMAGE"
    assert layer_image_type("gray") == "GRAYA_IMAGE"
    with pytest.raises(PixelFormatError, match="indexed"):
        layer_image_type("indexed")


def test_is_blank():
    assert is_blank(b"")
    assert is_blank(bytes(100))
    assert not is_blank(bytes(99) + b"\x01")
    assert not is_blank(memoryview(b"\x00\x00\x80\x3f"))  # float32 1.0
