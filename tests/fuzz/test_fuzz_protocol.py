"""The worker and the protocol reader under random streams: every request gets a well-formed reply of a
documented kind, and the worker stays usable."""

from __future__ import annotations

import io
import json
import socket
import threading

import numpy as np
import pytest
from engine_helpers import HELLO, converse
from fuzz_settings import FUZZ
from hypothesis import given
from hypothesis import strategies as st

from ssn_engine.loopback import authenticate
from ssn_engine.methods import load_method
from ssn_engine.host_kit.protocol import ProtocolError, read_message
from ssn_engine.worker import Worker

ERROR_TYPES = {"BadRequest", "EmptyAlpha", "LightMapError", "UnknownCutout", "ModelError"}
WORKER = Worker(load_method("geometric"))

json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-(10**12), 10**12) | st.floats(allow_nan=True) | st.text(max_size=12),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=12,
)
fields = st.sampled_from(
    ["cutout", "light_map", "preset", "color", "opacity", "format", "edits", "width", "camera", "token", "id"]
)


@st.composite
def requests(draw) -> bytes:
    """A request that is well framed but may say anything: random command, fields, buffers and payloads."""
    cmd = draw(st.sampled_from(list(Worker.COMMANDS) + ["shutdown", "auth", "", "x" * 40]) | json_values)
    header = {"id": draw(st.integers(0, 1000)), "cmd": cmd}
    header.update(draw(st.dictionaries(fields, json_values | st.sampled_from(["softbox", "c1", "uint16"]), max_size=4)))
    payload = b""
    if draw(st.booleans()):
        shape = draw(st.lists(st.integers(0, 40), min_size=1, max_size=3))
        dtype = draw(st.sampled_from(["uint8", "uint16", "float16", "float32"]))
        size = int(np.prod(shape)) * np.dtype(dtype).itemsize
        nbytes = size if draw(st.integers(0, 9)) else draw(st.integers(-5, size + 5))  # sometimes inconsistent
        payload = (draw(st.binary(min_size=1, max_size=64)) * (size + 6))[: max(0, nbytes)]  # as many as declared
        header["buffers"] = [
            {"name": draw(st.sampled_from(["alpha", "layer"])), "dtype": dtype, "shape": shape, "nbytes": nbytes}
        ]
    return json.dumps(header).encode() + b"\n" + payload


@st.composite
def nested(draw) -> bytes:
    """A header line nesting arrays and objects up to far past Python's recursion limit, balanced or not, alone
    or inside a request's field."""
    depth = draw(st.integers(1, 5) | st.integers(25, 40) | st.integers(900, 1100) | st.integers(10_000, 300_000))
    opener, closer = draw(st.sampled_from([(b"[", b"]"), (b'{"a":', b"}"), (b'[{"a":', b"}]")]))
    inner = opener * depth + b"1" + closer * draw(st.sampled_from([depth, depth // 2, 0]))
    if draw(st.booleans()):
        field = draw(fields)
        inner = b'{"id": 7, "cmd": "render", "cutout": "c1", "' + field.encode() + b'": ' + inner + b"}"
    return inner + b"\n"


@FUZZ
@given(stream=st.lists(requests() | nested() | st.binary(max_size=80).map(lambda b: b + b"\n"), min_size=1, max_size=4))
def test_random_requests_always_get_documented_replies(stream):
    try:
        replies, ended = converse(WORKER, b"".join(stream) + HELLO)
    except ProtocolError as exc:
        pytest.fail(f"the worker wrote a malformed reply: {exc}")
    for reply in replies:
        assert reply["ok"] is True or reply["error"]["type"] in ERROR_TYPES, reply
    if not ended:  # a random 'shutdown' ends the conversation; otherwise the final hello is answered
        assert replies[-1].get("id") == 99 and replies[-1]["ok"] is True


@FUZZ
@given(data=st.binary(max_size=300) | nested())
def test_the_reader_takes_any_bytes(data):
    """read_message on arbitrary bytes: a message, EOFError or ProtocolError, nothing else."""
    try:
        read_message(io.BytesIO(data))
    except (EOFError, ProtocolError):
        pass


@FUZZ
@given(data=st.binary(max_size=300) | nested() | requests())
def test_a_loopback_connection_takes_any_first_bytes(data):
    """authenticate on arbitrary first bytes: refused, with an Unauthorized reply where a line came."""
    ours, theirs = socket.socketpair()
    with ours, theirs:

        def send() -> None:
            theirs.sendall(data)
            theirs.shutdown(socket.SHUT_WR)

        sender = threading.Thread(target=send, daemon=True)
        sender.start()  # a long line fills the socket's buffer before authenticate reads it
        admitted = authenticate(ours, "secret")
        ours.close()
        reply = theirs.makefile("rb").readline()
        sender.join(timeout=10)
    assert not admitted
    assert not reply or json.loads(reply)["error"]["type"] == "Unauthorized"
