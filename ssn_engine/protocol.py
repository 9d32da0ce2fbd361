"""Message framing of the engine worker protocol (stdlib only).

A message is one line of UTF-8 JSON (the header) followed by the raw bytes of
the buffers its ``"buffers"`` list declares, in that order. Each buffer entry
is ``{"name", "dtype", "shape", "nbytes"}``; data is little-endian, C order.
See ``docs/protocol.md`` for the commands. The plug-ins import this module
(copied beside them at install time), so it must stay free of numpy.
"""

from __future__ import annotations

import json
from typing import BinaryIO

PROTOCOL_VERSION = 1
DTYPES = {"uint8": 1, "uint16": 2, "float16": 2, "float32": 4}
MAX_HEADER = 1 << 20


class ProtocolError(RuntimeError):
    """The stream does not hold a well-formed message."""


class Buffer:
    """Raw array bytes with their dtype name and shape."""

    __slots__ = ("data", "dtype", "shape")

    def __init__(self, dtype: str, shape: tuple[int, ...] | list[int], data: bytes | bytearray | memoryview):
        if dtype not in DTYPES:
            raise ProtocolError(f"unsupported dtype {dtype!r}; use one of {sorted(DTYPES)}")
        self.dtype, self.shape, self.data = dtype, tuple(int(s) for s in shape), data
        expected = DTYPES[dtype]
        for s in self.shape:
            expected *= s
        if len(memoryview(data).cast("B")) != expected:
            raise ProtocolError(f"buffer of shape {self.shape} {dtype} needs {expected} bytes, got {len(data)}")


def write_message(stream: BinaryIO, header: dict, buffers: dict[str, Buffer] | None = None) -> None:
    """Write one message and flush."""
    buffers = buffers or {}
    header = dict(header)
    header["buffers"] = [
        {"name": name, "dtype": b.dtype, "shape": list(b.shape), "nbytes": len(memoryview(b.data).cast("B"))}
        for name, b in buffers.items()
    ]
    stream.write(json.dumps(header, separators=(",", ":")).encode("utf-8") + b"\n")
    stream.writelines(memoryview(b.data).cast("B") for b in buffers.values())
    stream.flush()


def _read_exact(stream: BinaryIO, n: int) -> bytes:
    chunks, left = [], n
    while left:
        chunk = stream.read(left)
        if not chunk:
            raise EOFError(f"stream ended with {left} of {n} bytes unread")
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def read_message(stream: BinaryIO) -> tuple[dict, dict[str, Buffer]]:
    """Read one message; EOFError at a clean end of stream."""
    line = stream.readline(MAX_HEADER + 1)
    if not line:
        raise EOFError("stream closed")
    if not line.endswith(b"\n"):
        raise ProtocolError("header line too long or truncated")
    try:
        header = json.loads(line)
    except json.JSONDecodeError as exc:
        raise ProtocolError(f"header is not JSON: {exc}") from None
    if not isinstance(header, dict):
        raise ProtocolError("header must be a JSON object")
    buffers = {}
    for entry in header.pop("buffers", []) or []:
        try:
            name, dtype, shape, nbytes = entry["name"], entry["dtype"], entry["shape"], int(entry["nbytes"])
        except (KeyError, TypeError, ValueError):
            raise ProtocolError(f"malformed buffer entry {entry!r}") from None
        buffers[name] = Buffer(dtype, shape, _read_exact(stream, nbytes))
    return header, buffers
