"""The worker on a loopback socket (``ssn-shadow serve --port``) against other local programs: a connection must
authenticate first and within a deadline, and one that does not never holds the worker. Real sockets on
127.0.0.1, every wait bounded."""

from __future__ import annotations

import json
import os
import socket
import threading
import time

import pytest

from ssn_engine import loopback
from ssn_engine.host_kit.client import EngineClient
from ssn_engine.host_kit.protocol import PROTOCOL_VERSION
from ssn_engine.methods import load_method

TOKEN = "the-token"


@pytest.fixture(scope="module")
def port():
    """A worker serving in this process (geometric method); its port."""
    read_end, write_end = os.pipe()
    with os.fdopen(read_end) as announced, os.fdopen(write_end, "w") as announce:
        thread = threading.Thread(
            target=loopback.serve_tcp, args=(load_method("geometric"), 0, announce, TOKEN), daemon=True
        )
        thread.start()
        port = int(announced.readline().split()[1].rsplit(":", 1)[1])
    yield port
    EngineClient(address=("127.0.0.1", port), timeout=10, token=TOKEN).request("shutdown")
    thread.join(timeout=10)
    assert not thread.is_alive()


def _connect(port: int) -> socket.socket:
    conn = socket.create_connection(("127.0.0.1", port), timeout=10)
    conn.settimeout(10)
    return conn


def _reply_then_close(conn: socket.socket) -> tuple[dict, bytes]:
    """The one reply line a refused connection gets, and what follows it (b"": the worker closed it)."""
    with conn.makefile("rb") as reader:
        return json.loads(reader.readline()), reader.read()


def test_a_silent_or_half_sent_connection_does_not_hold_the_worker(port):
    silent, half = _connect(port), _connect(port)
    half.sendall(b'{"id": 1, "cmd": "au')
    try:
        start = time.monotonic()
        client = EngineClient(address=("127.0.0.1", port), timeout=loopback.AUTH_TIMEOUT - 1, token=TOKEN)
        assert client.request("hello")[0]["protocol"] == PROTOCOL_VERSION
        client.close()
        assert time.monotonic() - start < loopback.AUTH_TIMEOUT  # served before their deadline passed
    finally:
        silent.close()
        half.close()


@pytest.mark.parametrize(
    "first",
    [
        b"garbage\n",
        b'{"id": 1, "cmd": "hello"}\n',
        b'{"id": 1, "cmd": "auth", "token": "guess"}\n',
        b'{"id": 1, "cmd": "auth", "token": "\\ud800"}\n',  # a lone surrogate
        b'{"id": 1, "cmd": "auth", "token": ["the-token"]}\n',
        b'{"id": 1, "cmd": "auth", "token": "the-token", "buffers": [{"name": "alpha", "dtype": "uint8", '
        b'"shape": [1], "nbytes": 1}]}\n\x00',
        b"[" * 200_000 + b"]" * 200_000 + b"\n",
    ],
    ids=["garbage", "hello", "wrong-token", "surrogate-token", "list-token", "auth-with-buffer", "nested"],
)
def test_anything_but_auth_first_is_unauthorized_and_closed(port, first):
    with _connect(port) as conn:
        conn.sendall(first)
        reply, rest = _reply_then_close(conn)
    assert reply["ok"] is False and reply["error"]["type"] == "Unauthorized", reply
    assert "send auth first" in reply["error"]["message"] and rest == b""


def test_a_connection_that_never_authenticates_is_closed_at_the_deadline(port, monkeypatch):
    monkeypatch.setattr(loopback, "AUTH_TIMEOUT", 0.5)
    with _connect(port) as conn:
        conn.sendall(b'{"id": 1, "cmd": "auth", ')
        start = time.monotonic()
        reply, rest = _reply_then_close(conn)
    assert reply["error"]["type"] == "Unauthorized" and "within 0.5 s" in reply["error"]["message"]
    assert rest == b"" and time.monotonic() - start < 5


def test_authenticated_connections_are_served_one_at_a_time_in_order(port):
    """A second authenticated client waits for the first one to close, then gets its answers."""
    first = EngineClient(address=("127.0.0.1", port), timeout=10, token=TOKEN)
    assert first.request("hello")[0]["ok"] is True
    second = EngineClient(address=("127.0.0.1", port), timeout=10, token=TOKEN)
    answered = threading.Event()

    def ask() -> None:
        second.request("hello")
        answered.set()

    thread = threading.Thread(target=ask, daemon=True)
    thread.start()
    assert not answered.wait(0.5)  # the worker still talks to the first client
    first.close()
    assert answered.wait(10)
    second.close()
