"""The engine worker (ssn-shadow serve) through the stdlib client, as the plug-ins use it."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys

import numpy as np
import pytest
from engine_helpers import REPO, drawn_alpha

from ssn_engine.host_kit.client import EngineClient, EngineError, WorkerUnavailable
from ssn_engine.host_kit.light_map import PRESETS
from ssn_engine.host_kit.protocol import PROTOCOL_VERSION, Buffer

SERVE = [sys.executable, "-m", "ssn_engine", "serve"]
CANVAS_W, CANVAS_H = 400, 300


@pytest.fixture(scope="module")
def worker_env():
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv(
            "PYTHONPATH", str(REPO) + (os.pathsep + os.environ["PYTHONPATH"] if os.environ.get("PYTHONPATH") else "")
        )
        mp.delenv("SSN_SHADOW_MODEL_DIR", raising=False)
        yield


@pytest.fixture(scope="module")
def client(worker_env):
    c = EngineClient(command=SERVE, timeout=60)
    yield c
    c.close()


def buf(array: np.ndarray) -> Buffer:
    array = np.ascontiguousarray(array)
    return Buffer(array.dtype.name, array.shape, array.tobytes())


def arr(buffer: Buffer) -> np.ndarray:
    return np.frombuffer(buffer.data, np.dtype(buffer.dtype)).reshape(buffer.shape)


def canvas_alpha(dtype=np.uint8) -> np.ndarray:
    """The drawn post (160 x 120) at (140, 120) on a 400 x 300 canvas."""
    small = drawn_alpha(160, 120, np.float32)
    out = np.zeros((CANVAS_H, CANVAS_W), np.float32)
    out[120:240, 140:300] = small
    if dtype == np.uint8:
        return (out * 255).astype(np.uint8)
    if dtype == np.uint16:
        return (out * 65535).astype(np.uint16)
    return out.astype(dtype)


@pytest.fixture(scope="module")
def cutout(client):
    reply, _ = client.request("set_cutout", {"alpha": buf(canvas_alpha())})
    return reply


def _light(u, v, softness=0.002, intensity=2.0):
    return {
        "format": "ssn-shadow-elm",
        "version": 1,
        "lights": [{"u": u, "v": v, "softness": softness, "intensity": intensity}],
    }


def _bbox_of(alpha):
    ys, xs = np.nonzero(alpha > 0.01 * np.iinfo(alpha.dtype).max if alpha.dtype.kind == "u" else alpha > 0.01)
    return [int(xs.min()), int(ys.min()), int(xs.max()) + 1, int(ys.max()) + 1]


def test_hello(client):
    reply, buffers = client.request("hello")
    assert reply["ok"] is True and buffers == {}
    assert reply["protocol"] == PROTOCOL_VERSION
    assert reply["method"] in ("ssn", "geometric")
    assert isinstance(reply["method_note"], str) and reply["method_note"]
    assert reply["resolution"] == 256
    assert reply["presets"] == list(PRESETS)


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="pipe sizes are Linux's")
def test_the_worker_widens_its_reply_pipe(client):
    """A layer's megabytes reach the plug-in through a 1 MiB pipe (Krita reads a reply in a few reads, not
    hundreds of 64 KiB ones)."""
    import fcntl

    from ssn_engine.worker import PIPE_SIZE

    client.request("hello")
    assert fcntl.fcntl(client._proc.stdout.fileno(), fcntl.F_GETPIPE_SZ) == PIPE_SIZE >= 1 << 20


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32, np.float16])
def test_set_cutout_with_every_alpha_dtype(client, dtype):
    alpha = canvas_alpha(dtype)
    reply, _ = client.request("set_cutout", {"alpha": buf(alpha)})
    assert isinstance(reply["cutout"], str)
    assert reply["bbox"] == _bbox_of(canvas_alpha(np.uint8))
    _, ao = client.request("get_ao", cutout=reply["cutout"])
    assert arr(ao["ao"]).shape == (256, 256) and arr(ao["ao"]).dtype == np.uint8
    mask = arr(ao["mask"])
    assert mask.shape == (256, 256) and mask[8].max() > 128 and mask[:6].max() == 0
    client.request("release", cutout=reply["cutout"])


@pytest.mark.parametrize("dtype, top", [("uint8", 255), ("uint16", 65535), ("float16", 1.0), ("float32", 1.0)])
@pytest.mark.parametrize("channels", ["rgba", "bgra"])
def test_render_in_every_format(client, cutout, dtype, top, channels):
    reply, buffers = client.request(
        "render",
        cutout=cutout["cutout"],
        preset="softbox",
        color=[0.2, 0.4, 0.6],
        opacity=0.8,
        format={"dtype": dtype, "channels": channels},
    )
    layer = arr(buffers["layer"])
    assert buffers["layer"].dtype == dtype and layer.dtype == np.dtype(dtype)
    assert layer.shape == (reply["height"], reply["width"], 4)
    assert 0 <= reply["x"] and reply["x"] + reply["width"] <= CANVAS_W
    assert 0 <= reply["y"] and reply["y"] + reply["height"] <= CANVAS_H
    assert reply["method"] in ("ssn", "geometric") and set(reply["timing_ms"]) == {"shadow", "layer"}
    rgb = layer[..., :3].astype(np.float64) / top
    expected = [0.2, 0.4, 0.6] if channels == "rgba" else [0.6, 0.4, 0.2]
    assert np.allclose(rgb, expected, atol=1e-3)
    alpha = layer[..., 3].astype(np.float64) / top
    assert 0.3 < alpha.max() <= 0.8 + 1e-3  # A = opacity * s


def test_render_formats_agree(client, cutout):
    layers = {}
    for dtype, top in (("uint8", 255), ("float32", 1.0)):
        reply, buffers = client.request("render", cutout=cutout["cutout"], preset="two-lights", format={"dtype": dtype})
        layers[dtype] = (arr(buffers["layer"])[..., 3] / top, (reply["x"], reply["y"]))
    assert layers["uint8"][1] == layers["float32"][1]
    assert np.abs(layers["uint8"][0] - layers["float32"][0]).max() <= 0.5 / 255 + 1e-6


def _layer_mass(client, cutout_id, light_map):
    reply, buffers = client.request("render", cutout=cutout_id, light_map=light_map, format={"dtype": "float32"})
    full = np.zeros((CANVAS_H, CANVAS_W), np.float32)
    if reply["width"]:
        a = arr(buffers["layer"])[..., 3]
        full[reply["y"] : reply["y"] + reply["height"], reply["x"] : reply["x"] + reply["width"]] = a
    return reply, full


def test_layer_is_placed_per_framing(client, cutout):
    x0, y0, x1, y1 = cutout["bbox"]
    cx = 0.5 * (x0 + x1)
    alpha = canvas_alpha() > 127
    yy, xx = np.mgrid[0:CANVAS_H, 0:CANVAS_W]

    # light right of centre: shadow left of the object
    _, right = _layer_mass(client, cutout["cutout"], _light(0.75, 0.6))
    ground = right * ~alpha
    assert ground.sum() > 50
    assert (ground * xx).sum() / ground.sum() < cx - 10
    # light left of centre: shadow right of the object
    _, left = _layer_mass(client, cutout["cutout"], _light(0.25, 0.6))
    ground = left * ~alpha
    assert (ground * xx).sum() / ground.sum() > cx + 10
    # light straight ahead, low: below the object's base (towards the viewer)
    reply, ahead = _layer_mass(client, cutout["cutout"], _light(0.5, 0.7))
    ground = ahead * ~alpha
    assert ground[y1 + 2 :].sum() > 0.8 * ground.sum()
    assert reply["y"] + reply["height"] > y1
    # no shadow far above the object for any of these front lights
    for full in (right, left, ahead):
        assert full[: max(0, y0 - 5)].max(initial=0.0) < 1 / 255  # nothing an 8-bit layer would show


def test_no_light_gives_an_empty_layer(client, cutout):
    empty = {"format": "ssn-shadow-elm", "version": 1, "lights": []}
    reply, buffers = client.request("render", cutout=cutout["cutout"], light_map=empty)
    assert (reply["width"], reply["height"]) == (0, 0) and "layer" not in buffers
    assert "no light" in reply["no_shadow"]
    reply, _ = client.request("render", cutout=cutout["cutout"], preset="softbox")
    assert "no_shadow" not in reply


def test_edit_ao(client):
    reply, _ = client.request("set_cutout", {"alpha": buf(canvas_alpha())})
    key = reply["cutout"]
    _, before = client.request("get_ao", cutout=key)
    ao0 = arr(before["ao"])
    assert ao0.min() < 250  # some contact occlusion was predicted
    _, edited = client.request("edit_ao", cutout=key, edits=[{"op": "strength", "value": 0}])
    assert np.all(arr(edited["ao"]) == 255)
    _, now = client.request("get_ao", cutout=key)
    assert np.all(arr(now["ao"]) == 255)
    _, dark = client.request(
        "edit_ao", cutout=key, edits=[{"op": "brush", "x": 0.5, "y": 0.6, "radius": 0.05, "strength": -1}]
    )
    dark = arr(dark["ao"])
    assert dark[153, 128] < ao0[153, 128] and np.array_equal(dark[:100], ao0[:100])
    _, back = client.request("edit_ao", cutout=key, edits=[])  # undo everything
    assert np.array_equal(arr(back["ao"]), ao0)
    with pytest.raises(EngineError) as info:
        client.request("edit_ao", cutout=key, edits=[{"op": "grow", "pixels": "3"}])
    assert info.value.kind == "BadRequest" and "edits[0].pixels" in str(info.value)
    with pytest.raises(EngineError) as info:
        client.request("edit_ao", cutout=key, edits={"op": "grow"})
    assert info.value.kind == "BadRequest" and "edits" in str(info.value)


def test_preview_is_the_shadow_multiplied_onto_the_thumbnail(client):
    """A host's preview: the worker composites, hides the shadow under the cutout and draws the horizon, so the
    host's Python does no pixel maths."""
    from scipy import ndimage

    alpha = drawn_alpha(160, 120, np.uint16)  # a cutout at its own depth
    key = client.request("set_cutout", {"alpha": buf(alpha)})[0]["cutout"]
    background = np.full((120, 160, 4), 200, np.uint8)
    sent = {"background": buf(background)}
    reply, out = client.request("preview", sent, cutout=key, preset="high-sun", opacity=1.0)
    image = arr(out["image"])
    assert image.shape == (120, 160, 3) and image.dtype == np.uint8 and "no_shadow" not in reply
    assert image.min() < 120  # a dark contact shadow
    inside = ndimage.binary_erosion(alpha == alpha.max(), iterations=2)
    assert (image[inside] == 200).all()  # the cutout, above the shadow layer, hides it (its framed mask)
    with pytest.raises(EngineError, match="preview: unexpected buffer 'cover'; it takes background"):
        client.request("preview", {**sent, "cover": buf(alpha)}, cutout=key, preset="high-sun")
    red = client.request("preview", sent, cutout=key, preset="high-sun", color=[1.0, 0.0, 0.0], horizon=30.4)[1]
    red = arr(red["image"])
    assert (red[..., 0][alpha == 0] >= 199).all() and red[..., 1].min() < 120  # a red shadow keeps the red
    assert tuple(red[30, 0]) == (255, 140, 0) and tuple(red[30, 6]) != (255, 140, 0)  # dashed horizon
    dark = client.request("preview", sent, cutout=key, light_map={**_light(0.5, 0.2), "lights": []})
    assert dark[0]["no_shadow"] and (arr(dark[1]["image"]) == 200).all()
    with pytest.raises(EngineError, match="background: 80 x 40, but the cutout is 160 x 120") as info:
        client.request("preview", {"background": buf(background[:40, :80])}, cutout=key, preset="softbox")
    assert info.value.kind == "BadRequest"
    with pytest.raises(EngineError, match="background: expected uint8"):
        client.request("preview", {"background": buf(background[..., 0])}, cutout=key, preset="softbox")
    client.request("release", cutout=key)


def test_a_preview_of_a_large_canvas_is_its_shadow_scaled_down(client):
    """Krita's docker previews a light drag on a thumbnail of the whole canvas: the full-size cutout's shadow
    (its AO, edits and camera) drawn at the thumbnail's scale, hidden under the cutout without a cover sent."""
    alpha = drawn_alpha(800, 600)
    key = client.request("set_cutout", {"alpha": buf(alpha)})[0]["cutout"]
    background = np.full((150, 200, 4), 200, np.uint8)  # a quarter of the canvas
    reply, out = client.request("preview", {"background": buf(background)}, cutout=key, preset="low-sun-left")
    image = arr(out["image"])[..., 0].astype(np.float64)
    assert image.shape == (150, 200) and "no_shadow" not in reply
    layer = client.request("render", cutout=key, preset="low-sun-left", format={"dtype": "float32"})
    x, y, w, h = (layer[0][k] for k in ("x", "y", "width", "height"))
    full = np.zeros((600, 800), np.float64)
    full[y : y + h, x : x + w] = arr(layer[1]["layer"])[..., 3]
    expected = 200 * (1 - full.reshape(150, 4, 200, 4).mean(axis=(1, 3)))
    covered = alpha.reshape(150, 4, 200, 4).min(axis=(1, 3)) == 255
    assert (image[covered] >= 199).mean() > 0.95  # the cutout hides its shadow
    ground = ~alpha.reshape(150, 4, 200, 4).any(axis=(1, 3))
    assert expected[ground].min() < 150  # a real shadow to compare
    assert np.abs(image - expected)[ground].mean() < 0.5
    # at edges the two differ: a traced sun's crisp edge meets the network's soft shadow of it in a maximum
    # taken per preview pixel here, per canvas pixel there (a quarter of full darkness at most), and a crisp edge
    # swept through the read depth may fall one preview pixel over
    near = np.minimum.reduce(
        [np.abs(image - np.roll(expected, (dy, dx), (0, 1))) for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
    )
    assert near[ground].max() < 50
    with pytest.raises(EngineError, match="scaled down with its aspect ratio") as info:
        client.request("preview", {"background": buf(background[:100])}, cutout=key, preset="softbox")
    assert info.value.kind == "BadRequest"
    client.request("release", cutout=key)


@pytest.mark.parametrize(
    "cmd, params, buffers, kind, fragment",
    [
        ("set_cutout", {}, {"alpha": np.zeros((20, 30), np.uint8)}, "EmptyAlpha", "empty"),
        ("set_cutout", {}, {"alpha": np.full((20, 30), np.nan, np.float32)}, "EmptyAlpha", "empty"),
        ("set_cutout", {}, {}, "BadRequest", "alpha"),
        ("set_cutout", {}, {"alpha": np.ones((4, 5, 2), np.uint8)}, "BadRequest", "alpha"),
        ("render", {"cutout": "c999", "preset": "softbox"}, {}, "UnknownCutout", "c999"),
        ("get_ao", {"cutout": None}, {}, "UnknownCutout", "set_cutout"),
        ("frobnicate", {}, {}, "BadRequest", "frobnicate"),
        ("render", {"cutout": "c999", "preset": "sunset-glow"}, {}, "LightMapError", "sunset-glow"),
        ("preview", {"cutout": "c999"}, {}, "BadRequest", "light_map or preset"),
        (
            "render",
            {
                "cutout": "c999",
                "light_map": {
                    "format": "ssn-shadow-elm",
                    "version": 1,
                    "lights": [
                        {"u": 0.5, "v": 0.5, "softness": 0.01, "intensity": 1},
                        {"u": 1.5, "v": 0.5, "softness": 0.01, "intensity": 1},
                    ],
                },
            },
            {},
            "LightMapError",
            "lights[1].u",
        ),
        (
            "render",
            {"cutout": "c999", "light_map": {"format": "ssn-shadow-elm", "version": 7, "lights": []}},
            {},
            "LightMapError",
            "version",
        ),
    ],
)
def test_errors_and_the_worker_survives(client, cmd, params, buffers, kind, fragment):
    with pytest.raises(EngineError) as info:
        client.request(cmd, {k: buf(v) for k, v in buffers.items()} or None, **params)
    assert info.value.kind == kind
    assert fragment in str(info.value)
    assert not isinstance(info.value, WorkerUnavailable)
    reply, _ = client.request("hello")  # still serving
    assert reply["protocol"] == PROTOCOL_VERSION


@pytest.mark.parametrize(
    "params, kind, fragment",
    [
        ({"preset": "no-such-preset"}, "LightMapError", "no-such-preset"),
        (
            {
                "light_map": {
                    "format": "ssn-shadow-elm",
                    "version": 1,
                    "lights": [{"u": 0.5, "v": 0.5, "softness": 0.01}],
                }
            },
            "LightMapError",
            "lights[0].intensity",
        ),
        ({"preset": "softbox", "format": {"dtype": "int8"}}, "BadRequest", "dtype"),
        ({"preset": "softbox", "format": {"channels": "argb"}}, "BadRequest", "channels"),
        ({"preset": "softbox", "format": "uint8"}, "BadRequest", "format"),
        ({"preset": "softbox", "opacity": 3}, "BadRequest", "opacity"),
        ({"preset": "softbox", "color": [1, 2, 3]}, "BadRequest", "color"),
        ({"preset": "softbox", "margin": -1}, "BadRequest", "margin"),
        ({"preset": "softbox", "margin": 2.5}, "BadRequest", "margin"),
    ],
)
def test_render_errors(client, cutout, params, kind, fragment):
    with pytest.raises(EngineError) as info:
        client.request("render", cutout=cutout["cutout"], **params)
    assert info.value.kind == kind and fragment in str(info.value)
    reply, _ = client.request("render", cutout=cutout["cutout"], preset="softbox")
    assert reply["width"] > 0


def test_release(client):
    reply, _ = client.request("set_cutout", {"alpha": buf(canvas_alpha())})
    client.request("release", cutout=reply["cutout"])
    with pytest.raises(EngineError) as info:
        client.request("get_ao", cutout=reply["cutout"])
    assert info.value.kind == "UnknownCutout"


def test_killed_worker_is_reported_then_restarted(worker_env):
    c = EngineClient(command=SERVE, timeout=60)
    try:
        c.request("hello")
        key = c.request("set_cutout", {"alpha": buf(canvas_alpha())})[0]["cutout"]
        c._proc.kill()
        c._proc.wait(timeout=10)
        with pytest.raises(WorkerUnavailable, match="restart"):
            c.request("render", cutout=key, preset="softbox")
        reply, _ = c.request("hello")  # a fresh worker
        assert reply["protocol"] == PROTOCOL_VERSION and c.running
        with pytest.raises(EngineError) as info:  # which has forgotten the old cutout
            c.request("render", cutout=key, preset="softbox")
        assert info.value.kind == "UnknownCutout"
    finally:
        c.close()


def test_hung_worker_times_out(worker_env):
    silent = [sys.executable, "-c", "import sys, time\nsys.stdin.buffer.readline()\ntime.sleep(60)"]
    c = EngineClient(command=silent, timeout=1.5)
    try:
        with pytest.raises(WorkerUnavailable, match="did not answer 'hello'"):
            c.request("hello")
        assert not c.running
    finally:
        c.close()


def test_missing_engine_command(worker_env):
    c = EngineClient(command=["/nonexistent/python-for-ssn", "-m", "ssn_engine", "serve"])
    with pytest.raises(WorkerUnavailable, match="could not start"):
        c.request("hello")


def test_client_needs_exactly_one_target():
    with pytest.raises(ValueError):
        EngineClient()
    with pytest.raises(ValueError):
        EngineClient(command=SERVE, address=("127.0.0.1", 1))


def test_shutdown_then_a_fresh_worker(worker_env):
    c = EngineClient(command=SERVE, timeout=60)
    try:
        c.request("hello")
        proc = c._proc
        c.request("shutdown")
        assert proc.wait(timeout=10) is not None
        reply, _ = c.request("hello")  # a clean shutdown is not a crash: starts a new worker
        assert reply["protocol"] == PROTOCOL_VERSION
    finally:
        c.close()


def test_tcp_mode(worker_env):
    proc = subprocess.Popen(SERVE + ["--port", "0"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        _, address, token = proc.stdout.readline().split()
        assert address.startswith("127.0.0.1:") and token.startswith("token=")
        port, token = int(address.rsplit(":", 1)[1]), token.removeprefix("token=")
        with pytest.raises(WorkerUnavailable, match="refused this plug-in's token"):
            EngineClient(address=("127.0.0.1", port), timeout=60, token="guess").request("hello")
        with socket.create_connection(("127.0.0.1", port)) as raw:  # no auth: refused before any work
            raw.sendall(b'{"id": 1, "cmd": "set_cutout"}\n')
            reply = json.loads(raw.makefile("rb").readline())
            assert reply["error"]["type"] == "Unauthorized" and raw.recv(1) == b""  # and the connection ends
        c = EngineClient(address=("127.0.0.1", port), timeout=60, token=token)
        reply, _ = c.request("hello")
        assert reply["protocol"] == PROTOCOL_VERSION
        key = c.request("set_cutout", {"alpha": buf(canvas_alpha(np.uint16))})[0]["cutout"]
        reply, buffers = c.request(
            "render", cutout=key, preset="softbox", format={"dtype": "uint16", "channels": "bgra"}
        )
        assert arr(buffers["layer"]).shape == (reply["height"], reply["width"], 4)
        c.close()
        # each connection is a fresh conversation with the same worker
        c2 = EngineClient(address=("127.0.0.1", port), timeout=60, token=token)
        assert c2.request("hello")[0]["protocol"] == PROTOCOL_VERSION
        c2.request("shutdown")
        assert proc.wait(timeout=10) == 0
        with pytest.raises(WorkerUnavailable, match=str(port)):
            c2.request("hello")  # nobody is listening any more
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait(timeout=10)
        proc.stdout.close()


def test_stdio_bad_headers_get_replies_and_the_worker_goes_on(worker_env):
    """Garbage, then a header declaring a 10 GB buffer that never comes, then hello: two refusals at once (the
    10 GB are never waited for) and an answer; the worker ends cleanly with its input."""
    lines = [
        b"this is not json\n",
        json.dumps(
            {
                "id": 2,
                "cmd": "set_cutout",
                "buffers": [{"name": "alpha", "dtype": "uint8", "shape": [100000, 100000], "nbytes": 10**10}],
            }
        ).encode()
        + b"\n",
        b'{"id": 3, "cmd": "hello"}\n',
    ]
    result = subprocess.run(SERVE, input=b"".join(lines), capture_output=True, timeout=60)
    replies = [json.loads(line) for line in result.stdout.splitlines()]
    assert [r["ok"] for r in replies] == [False, False, True], replies
    assert replies[0]["error"]["type"] == replies[1]["error"]["type"] == "BadRequest"
    assert "limit" in replies[1]["error"]["message"] and replies[2]["id"] == 3
    assert result.returncode == 0


def test_set_cutout_with_a_camera_changes_the_geometric_shadow():
    """The horizon the artist sets reaches the method: a geometric worker casts a different shadow."""
    from ssn_engine.methods import load_method
    from ssn_engine.worker import Worker

    worker = Worker(load_method("geometric"))
    layers = []
    for camera in (None, {"horizon": -400.0, "fov": 40.0}):
        header = {} if camera is None else {"camera": camera}
        reply, _ = worker.set_cutout(header, {"alpha": buf(canvas_alpha())})
        _, out = worker.render({"cutout": reply["cutout"], "light_map": _light(0.0, 0.7)}, {})
        layers.append(arr(out["layer"])[..., 3].astype(float))
    assert layers[0].shape != layers[1].shape or np.abs(layers[0] - layers[1]).mean() > 1.0


def test_a_blind_preview_draws_the_horizon_the_model_read(client):
    """Without a horizon of the artist's, a preview can show the one the model read from the outline (dotted
    blue, at the thumbnail's scale), so a wrong perspective has a visible cause; an artist's horizon is drawn
    instead, and a cutout given a camera has no reading to draw."""
    alpha = np.pad(drawn_alpha(160, 120), ((100, 0), (0, 0)))  # sky above the post: the reading lies inside
    reply, _ = client.request("set_cutout", {"alpha": buf(alpha)})
    key, read = reply["cutout"], reply["camera_read"]
    assert 10 < read["horizon"] < 200
    for width, height in ((160, 220), (80, 110)):
        background = {"background": buf(np.zeros((height, width, 3), np.uint8))}
        image = arr(client.request("preview", background, cutout=key, preset="softbox", read_horizon=True)[1]["image"])
        blue = np.all(image == (40, 170, 255), axis=-1)
        row = int(np.floor(read["horizon"] * width / 160))
        assert blue[row, ::2].all() and not blue[row, 1::2].any() and blue.sum() == blue[row].sum()
        plain = arr(client.request("preview", background, cutout=key, preset="softbox")[1]["image"])
        assert not np.all(plain == (40, 170, 255), axis=-1).any()  # only when asked for
        set_row = arr(
            client.request("preview", background, cutout=key, preset="softbox", read_horizon=True, horizon=5.0)[1][
                "image"
            ]
        )
        assert tuple(set_row[5, 0]) == (255, 140, 0) and not np.all(set_row == (40, 170, 255), axis=-1).any()
    with pytest.raises(EngineError, match="read_horizon: expected true or false") as info:
        client.request("preview", background, cutout=key, preset="softbox", read_horizon="yes")
    assert info.value.kind == "BadRequest"
    given = client.request("set_cutout", {"alpha": buf(alpha)}, camera={"horizon": 30.0, "fov": 45.0})[0]["cutout"]
    background = {"background": buf(np.zeros((220, 160, 3), np.uint8))}
    image = arr(client.request("preview", background, cutout=given, preset="softbox", read_horizon=True)[1]["image"])
    assert not np.all(image == (40, 170, 255), axis=-1).any()
    for k in (key, given):
        client.request("release", cutout=k)


@pytest.mark.parametrize(
    "camera, fragment",
    [
        ({"fov": 40.0}, "camera"),
        ("low", "camera"),
        ({"horizon": 10.0, "fov": 0.0}, "camera.fov"),
    ],
)
def test_bad_camera_is_a_bad_request(client, camera, fragment):
    with pytest.raises(EngineError) as info:
        client.request("set_cutout", {"alpha": buf(canvas_alpha())}, camera=camera)
    assert info.value.kind == "BadRequest" and fragment in str(info.value)


def test_a_cutout_without_a_camera_says_which_one_the_model_read(client):
    """Blind, the shipped model reads the camera from the outline and says so in canvas terms (where an artist
    can start to set it); given a camera, there is nothing to report."""
    alpha = canvas_alpha(np.uint8)
    reply, _ = client.request("set_cutout", {"alpha": buf(alpha)})
    read = reply["camera_read"]
    assert set(read) == {"horizon", "fov"} and 10.0 < read["fov"] < 120.0
    assert -10 * CANVAS_H < read["horizon"] < 10 * CANVAS_H
    given, _ = client.request("set_cutout", {"alpha": buf(alpha)}, camera=read)
    assert "camera_read" not in given
    for key in (reply["cutout"], given["cutout"]):
        client.request("release", cutout=key)


def test_a_clipped_layer_reaches_past_the_canvas_by_its_margin_only(client):
    """A long shadow near the canvas's right edge: clipped to the canvas, to the canvas grown by a margin (the
    same pixels where both cover it), or kept whole."""
    alpha = np.zeros((CANVAS_H, CANVAS_W), np.uint8)
    alpha[100:260, 330:390] = (drawn_alpha(60, 160, np.float32) * 255).astype(np.uint8)
    reply, _ = client.request("set_cutout", {"alpha": buf(alpha)})
    sun = _light(0.25, 0.92, 0.0005, 2.0)  # 7 degrees up, left of forward: a long shadow to the right
    layers = {}
    for name, params in {"canvas": {}, "margin": {"margin": 40}, "whole": {"clip": False}}.items():
        header, buffers = client.request("render", cutout=reply["cutout"], light_map=sun, **params)
        layers[name] = header, arr(buffers["layer"])[..., 3]
    (canvas, a), (grown, b), (whole, _) = layers["canvas"], layers["margin"], layers["whole"]
    assert canvas["x"] + canvas["width"] == CANVAS_W
    assert grown["x"] + grown["width"] == CANVAS_W + 40 < whole["x"] + whole["width"]
    assert grown["y"] >= -40 and grown["x"] >= -40
    dy, dx = canvas["y"] - grown["y"], canvas["x"] - grown["x"]
    np.testing.assert_array_equal(b[dy : dy + a.shape[0], dx : dx + a.shape[1]], a)


class CountingWriter:
    """A client's writer that counts the bytes it sends."""

    def __init__(self, inner):
        self.inner, self.sent = inner, 0

    def writelines(self, chunks):
        chunks = [bytes(c) for c in chunks]
        self.sent += sum(len(c) for c in chunks)
        self.inner.writelines(chunks)

    def write(self, data):
        self.sent += len(data)
        return self.inner.write(data)

    def flush(self):
        self.inner.flush()


def test_a_camera_change_sends_the_camera_not_the_alpha(client):
    """set_camera gives a cutout a new camera: a few hundred bytes on the wire, no alpha-sized buffer; the AO is
    predicted again with it, the AO edits are kept, and the model's reading comes back when it is unset."""
    alpha = canvas_alpha()
    reply, _ = client.request("set_cutout", {"alpha": buf(alpha)})
    key, read = reply["cutout"], reply.get("camera_read")
    client.request("edit_ao", cutout=key, edits=[{"op": "strength", "value": 0.5}])
    _, before = client.request("get_ao", cutout=key)
    counting = CountingWriter(client._writer)
    client._writer = counting
    try:
        reply, _ = client.request("set_camera", cutout=key, camera={"horizon": -400.0, "fov": 40.0})
    finally:
        client._writer = counting.inner
    assert counting.sent < 200 < alpha.nbytes  # the header alone
    assert reply["cutout"] == key and "camera_read" not in reply  # the image's camera: nothing read
    _, after = client.request("get_ao", cutout=key)
    assert not np.array_equal(arr(before["ao"]), arr(after["ao"]))  # analysed again with the camera
    fresh = client.request("set_cutout", {"alpha": buf(alpha)}, camera={"horizon": -400.0, "fov": 40.0})[0]["cutout"]
    _, edited = client.request("edit_ao", cutout=fresh, edits=[{"op": "strength", "value": 0.5}])
    assert np.array_equal(arr(after["ao"]), arr(edited["ao"]))  # the edits kept: as a new cutout with them
    reply, _ = client.request("set_camera", cutout=key, camera=None)
    assert reply.get("camera_read") == read  # back to the model's own reading
    with pytest.raises(EngineError, match="camera"):
        client.request("set_camera", cutout=key)
    with pytest.raises(EngineError, match="camera.fov"):
        client.request("set_camera", cutout=key, camera={"horizon": 10.0, "fov": 179.0})
    with pytest.raises(EngineError) as unknown:
        client.request("set_camera", cutout="nope", camera=None)
    assert unknown.value.kind == "UnknownCutout"
    for k in (key, fresh):
        client.request("release", cutout=k)


def test_a_worker_of_another_protocol_is_refused():
    """The client's handshake: a worker that answers hello with another protocol version is stopped, with a
    message that says how to make the plug-in and the engine match."""
    script = (
        "import json, sys, time; rid = json.loads(sys.stdin.buffer.readline())['id']; "
        "sys.stdout.buffer.write(json.dumps({'id': rid, 'ok': True, 'protocol': 999}).encode() + b'\\n'); "
        "sys.stdout.flush(); time.sleep(30)"
    )
    c = EngineClient(command=[sys.executable, "-c", script], timeout=30)
    with pytest.raises(WorkerUnavailable, match="protocol 999, this plug-in") as refused:
        c.request("set_cutout", {"alpha": buf(canvas_alpha())})
    assert "install-plugin" in str(refused.value) and not c.running
