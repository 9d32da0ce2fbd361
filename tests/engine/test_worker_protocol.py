"""The worker against bad input: every header is checked before its buffers are read, every request gets a
reply, and the worker stays usable (in-process, over byte streams; random streams: tests/fuzz)."""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from engine_helpers import HELLO, converse

from ssn_engine.methods import load_method
from ssn_engine.host_kit.protocol import read_message
from ssn_engine.worker import MAX_REQUEST_BYTES, Worker


@pytest.fixture(scope="module")
def worker() -> Worker:
    return Worker(load_method("geometric"))


def message(header: dict, payload: bytes = b"") -> bytes:
    return json.dumps(header).encode() + b"\n" + payload


def alpha_entry(shape, dtype="uint8", nbytes=None, name="alpha") -> dict:
    size = int(np.prod(shape)) * np.dtype(dtype).itemsize if nbytes is None else nbytes
    return {"name": name, "dtype": dtype, "shape": list(shape), "nbytes": size}


@pytest.mark.parametrize(
    "header, payload, fragment",
    [
        ({"cmd": "launch", "buffers": [alpha_entry((4, 4))]}, bytes(16), "unknown command 'launch'"),
        ({"cmd": "set_cutout", "buffers": [alpha_entry((4, 4), "int64", 16)]}, bytes(16), "unsupported dtype"),
        ({"cmd": "set_cutout", "buffers": [alpha_entry((4, 4), nbytes=20)]}, bytes(20), "needs 16 bytes"),
        ({"cmd": "set_cutout", "buffers": [alpha_entry((1, 1, 1, 1, 4), nbytes=4)]}, bytes(4), "at most 4"),
        ({"cmd": "set_cutout", "buffers": [alpha_entry((4,))]}, bytes(4), "2D"),
        ({"cmd": "set_cutout", "buffers": [alpha_entry((2, 2)), alpha_entry((2, 2))]}, bytes(8), "once"),
        ({"cmd": "set_cutout", "buffers": [alpha_entry((1, 40000))]}, bytes(40000), "canvas is above"),
        ({"cmd": "render", "buffers": [alpha_entry((2, 2), name="layer")]}, bytes(4), "unexpected buffer 'layer'"),
        ({"cmd": "set_cutout", "buffers": [alpha_entry((2, 2), name="mask")]}, bytes(4), "it takes alpha"),
        ({"cmd": "set_cutout", "buffers": [alpha_entry((65536, 65536))]}, b"", "limit of 1 GiB"),
        (
            {"cmd": "set_cutout", "buffers": [{"name": "alpha", "dtype": "uint8", "shape": [2], "nbytes": -2}]},
            b"",
            "nbytes >= 0",
        ),
        ({"cmd": "set_cutout", "buffers": "alpha"}, b"", "must be a list"),
        (
            {"cmd": "set_cutout", "buffers": [alpha_entry((2, 2), "float32", 16) | {"shape": [2, "2"]}]},
            bytes(16),
            "shape must be",
        ),
    ],
)
def test_bad_header_is_refused_and_the_next_request_answered(worker, header, payload, fragment):
    replies, ended = converse(worker, message({"id": 1, **header}, payload) + HELLO)
    assert not ended and len(replies) == 2, replies
    assert replies[0]["ok"] is False and replies[0]["error"]["type"] == "BadRequest"
    assert fragment in replies[0]["error"]["message"]
    assert replies[1] == {**replies[1], "id": 99, "ok": True}  # the stream is still in step


def test_a_refused_declared_size_is_never_read(worker):
    """A header declaring more than the limit is refused at once; bytes that arrive after it anyway (here 3 MiB
    of binary) are dropped until the next header."""
    declared = message({"id": 1, "cmd": "set_cutout", "buffers": [alpha_entry((1, MAX_REQUEST_BYTES + 1))]})
    junk = np.random.default_rng(0).integers(0, 256, 3 << 20, dtype=np.uint8).tobytes().replace(b"\n", b" ")
    replies, _ = converse(worker, declared + junk + b"\n" + HELLO)
    assert [r["ok"] for r in replies] == [False, True] and "limit" in replies[0]["error"]["message"]


@pytest.mark.parametrize(
    "line",
    [
        b"[" * 200_000 + b"]" * 200_000,  # past Python's recursion limit
        b'{"id": 1, "cmd": "hello", "x": ' + b"[" * 600 + b"]" * 600 + b"}",  # within it, past the protocol's
        b'{"id": 1, "cmd": "render", "cutout": "c1", "light_map": ' + b'{"a": ' * 40 + b"1" + b"}" * 41,
    ],
    ids=["200000-deep", "600-deep-field", "40-deep-light-map"],
)
def test_deeply_nested_json_is_refused_and_the_worker_goes_on(worker, line):
    replies, ended = converse(worker, line + b"\n" + HELLO)
    assert not ended and len(replies) == 2, replies
    assert replies[0]["error"]["type"] == "BadRequest" and "nested more than 32" in replies[0]["error"]["message"]
    assert replies[1] == {**replies[1], "id": 99, "ok": True}


@pytest.mark.parametrize("value", [np.inf, -np.inf, -0.5])
def test_a_float_alpha_must_hold_coverage_from_0_to_1(worker, value):
    alpha = np.zeros((40, 50), np.float32)
    alpha[10:30, 20:30] = 1.0
    alpha[12, 22] = value
    replies, _ = converse(
        worker,
        message({"id": 1, "cmd": "set_cutout", "buffers": [alpha_entry(alpha.shape, "float32")]}, alpha.tobytes()),
    )
    assert replies[0]["ok"] is False and replies[0]["error"]["type"] == "BadRequest"
    assert f"alpha: a float alpha holds coverage from 0 to 1, got {value:g}" in replies[0]["error"]["message"]


def _small_cutout_with(worker, camera: dict) -> dict:
    """set_cutout's reply for a small cutout on a large canvas (the frame sees it much enlarged) and ``camera``."""
    alpha = np.zeros((1800, 1800), np.uint8)
    alpha[900:910, 900:905] = 255
    replies, _ = converse(
        worker,
        message(
            {"id": 1, "cmd": "set_cutout", "camera": camera, "buffers": [alpha_entry(alpha.shape)]}, alpha.tobytes()
        ),
    )
    return replies[0]


def test_a_horizon_out_of_reach_is_answered_in_canvas_rows(worker):
    reply = _small_cutout_with(worker, {"horizon": 1e9})
    fragment = "horizon: row 1e+09 is too far from the cutout for the model; give a canvas row from"
    assert reply["error"]["type"] == "BadRequest" and fragment in reply["error"]["message"], reply
    assert "frame" not in reply["error"]["message"] and "focal" not in reply["error"]["message"]


@pytest.mark.parametrize("fov", [1, 40, 170])
def test_any_field_of_view_the_engine_takes_is_taken_for_a_small_cutout(worker, fov):
    """The image's field of view is the photograph's, not the cutout's: a fragment on a large canvas takes it."""
    assert _small_cutout_with(worker, {"horizon": 800, "fov": fov})["ok"] is True


@pytest.mark.parametrize("cmd", ["get_ao", "render", "release"])
@pytest.mark.parametrize("key", [[1], {"c": 1}, 1])
def test_a_cutout_id_that_is_no_string_is_named(worker, cmd, key):
    replies, _ = converse(worker, message({"id": 1, "cmd": cmd, "cutout": key, "preset": "softbox"}) + HELLO)
    assert replies[0]["error"]["type"] == "BadRequest", replies[0]
    assert f"cutout: expected an id that set_cutout answered (a string), got {key!r}" in replies[0]["error"]["message"]
    assert replies[1]["ok"] is True


def test_a_real_cutout_after_refusals(worker):
    """Refusals leave no state behind: a real set_cutout and render still work on the same stream."""
    alpha = np.zeros((60, 80), np.uint8)
    alpha[20:50, 30:45] = 255
    stream = message({"id": 1, "cmd": "set_cutout", "buffers": [alpha_entry((3, 3), nbytes=5)]}, bytes(5)) + message(
        {"id": 2, "cmd": "set_cutout", "buffers": [alpha_entry(alpha.shape)]}, alpha.tobytes()
    )
    replies, _ = converse(worker, stream)
    assert replies[0]["ok"] is False and replies[1]["ok"] is True
    render = message({"id": 3, "cmd": "render", "cutout": replies[1]["cutout"], "preset": "softbox"})
    replies, _ = converse(worker, render)
    assert replies[0]["ok"] is True and replies[0]["width"] > 0


def test_the_sans_io_decoder_reads_what_the_worker_writes_in_any_pieces(worker):
    """Krita's QProcess client feeds MessageDecoder whatever arrives: the same messages as the stream reader."""
    from ssn_engine.host_kit.protocol import MessageDecoder

    alpha = np.zeros((40, 50), np.uint8)
    alpha[10:35, 20:30] = 255
    stream = message({"id": 1, "cmd": "set_cutout", "buffers": [alpha_entry(alpha.shape)]}, alpha.tobytes())
    stream += message({"id": 2, "cmd": "get_ao", "cutout": "c1"}) + HELLO
    writer = io.BytesIO()
    worker.sessions.clear()
    worker._ids = iter(range(1, 100))
    worker.serve(io.BytesIO(stream), writer)
    data = writer.getvalue()
    expected = []
    reader = io.BytesIO(data)
    while reader.tell() < len(data):
        expected.append(read_message(reader))
    for piece in (1, 7, 4096, len(data)):
        decoder, got = MessageDecoder(), []
        for i in range(0, len(data), piece):
            got += decoder.feed(data[i : i + piece])
        assert [h for h, _ in got] == [h for h, _ in expected]
        assert [{k: bytes(b.data) for k, b in bufs.items()} for _, bufs in got] == [
            {k: bytes(b.data) for k, b in bufs.items()} for _, bufs in expected
        ]
    assert len(expected) == 3 and "ao" in expected[1][1]
