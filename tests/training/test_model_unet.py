"""The U-Nets: shapes, configurable width and depth, the ELM injection, complexity report."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")

from training.model import AOPNet, SRNet, UNetConfig, build  # noqa: E402
from training.model.complexity import count_macs, count_parameters, describe  # noqa: E402

TINY = UNetConfig(widths=(4, 8, 8), groups=2, resolution=32)


@pytest.mark.parametrize("widths", [(4, 8), (4, 8, 8), (4, 8, 16, 16)])
def test_shapes_for_any_depth(widths):
    cfg = UNetConfig(widths=widths, groups=2, resolution=32)
    x = torch.rand(2, 1, 32, 32)
    assert AOPNet(cfg)(x).shape == (2, 1, 32, 32)
    assert SRNet(cfg)(x, x, torch.rand(2, 16, 32)).shape == (2, 1, 32, 32)


def test_encoder_downsamples_and_uses_groupnorm():
    net = build("aop", UNetConfig(widths=(4, 8, 16), groups=2))
    strides = [m.stride[0] for m in net.modules() if isinstance(m, torch.nn.Conv2d) and m.kernel_size == (3, 3)]
    assert strides.count(2) == 2
    assert any(isinstance(m, torch.nn.GroupNorm) for m in net.modules())


def test_sr_output_depends_on_the_elm():
    torch.manual_seed(0)
    net = SRNet(TINY).eval()
    x = torch.rand(1, 1, 32, 32)
    a = net(x, x, torch.zeros(1, 16, 32))
    e = torch.zeros(1, 16, 32)
    e[0, 3, 7] = 1
    assert (net(x, x, e) - a).abs().max() > 1e-4


def test_sr_bottleneck_takes_the_flattened_elm():
    net = SRNet(TINY)
    assert net.unet.inject[0].in_channels == 8 + 16 * 32


def test_head_bias_and_complexity_report():
    net = build("aop", TINY, head_bias=1.0)
    assert float(net.unet.head.bias) == 1.0
    assert count_parameters(net) > 0
    assert count_macs(net, torch.zeros(1, 1, 32, 32)) > 32 * 32 * 9 * 4
    text = describe("sr", build("sr", TINY), 32)
    assert "parameters" in text and "multiply-adds" in text


def test_config_round_trip():
    cfg = UNetConfig(widths=(8, 16), groups=4, resolution=64)
    assert UNetConfig.from_dict(cfg.to_dict()) == cfg
    cam = UNetConfig(widths=(8, 16), groups=4, resolution=64, camera=True)
    assert UNetConfig.from_dict(cam.to_dict()) == cam


def test_a_camera_taking_aop_sees_where_the_horizon_lies():
    """The camera input enters as rows' offsets below the horizon (in frames) and the focal length: the same mask
    under another horizon gets another AO map."""
    from training.model.unet import FOCAL_CENTRE, camera_maps

    maps = camera_maps(torch.tensor([[0.25, 1.5]]), 4)
    assert torch.allclose(maps[0, 0, :, 0], torch.tensor([-0.125, 0.125, 0.375, 0.625]))
    assert torch.allclose(maps[0, 1], torch.full((4, 4), 1.5 - FOCAL_CENTRE))
    torch.manual_seed(0)
    net = AOPNet(UNetConfig(widths=(4, 8, 8), groups=2, resolution=32, camera=True)).eval()
    x = torch.rand(1, 1, 32, 32)
    level, high = net(x, torch.tensor([[0.6, 1.2]])), net(x, torch.tensor([[-0.4, 1.2]]))
    assert level.shape == (1, 1, 32, 32) and (level - high).abs().max() > 1e-4
    assert "parameters" in describe("aop", net, 32)


def test_mirror_average_is_the_mean_of_the_two_passes():
    from training.model import MirrorAverage

    torch.manual_seed(0)
    net = build("sr", UNetConfig(resolution=32, widths=(4, 8, 8), groups=2)).eval()
    m, ao, elm = torch.rand(2, 1, 32, 32), torch.rand(2, 1, 32, 32), torch.rand(2, 16, 32)
    with torch.no_grad():
        got = MirrorAverage(net)(m, ao, elm)
        want = 0.5 * (net(m, ao, elm) + net(m.flip(-1), ao.flip(-1), elm.flip(-1)).flip(-1))
    torch.testing.assert_close(got, want, atol=1e-6, rtol=1e-5)


def test_ensemble_is_the_mean_of_its_members(tmp_path):
    from training import checkpoint
    from training.model import Ensemble

    torch.manual_seed(0)
    cfg = UNetConfig(resolution=32, widths=(4, 8, 8), groups=2)
    nets = [build("aop", cfg).eval() for _ in range(2)]
    m = torch.rand(2, 1, 32, 32)
    with torch.no_grad():
        torch.testing.assert_close(Ensemble(nets)(m), 0.5 * (nets[0](m) + nets[1](m)), atol=1e-6, rtol=1e-5)
    paths = []
    for k, (module, net) in enumerate([("aop", nets[0]), ("aop", nets[1]), ("sr", build("sr", cfg))]):
        paths.append(tmp_path / f"{k}.pt")
        checkpoint.save(paths[-1], {"module": module, "unet": cfg.to_dict(), "model": net.state_dict()})
    loaded, cks = checkpoint.load_models(paths[:2])
    assert isinstance(loaded, Ensemble) and len(cks) == 2
    with torch.no_grad():
        torch.testing.assert_close(loaded(m), Ensemble(nets)(m), atol=1e-6, rtol=1e-5)
    assert not isinstance(checkpoint.load_models(paths[:1])[0], Ensemble)  # one checkpoint: the network itself
    with pytest.raises(ValueError, match="different modules"):
        checkpoint.load_models(paths)
