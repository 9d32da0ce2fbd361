"""Message framing of the engine worker protocol (stdlib only).

A message is one line of UTF-8 JSON (the header) followed by the raw bytes of
the buffers its ``"buffers"`` list declares, in that order. Each buffer entry
is ``{"name", "dtype", "shape", "nbytes"}``; data is little-endian, C order.
See ``docs/protocol.md`` for the commands. The plug-ins import this module
(copied beside them at install time), so it must stay free of numpy.
"""

from __future__ import annotations

import json
import math
from typing import IO, Any, NamedTuple

PROTOCOL_VERSION = 3  # 2: set_camera; 3: set_geometry, set_cutout's lift and thickness
DTYPES = {"uint8": 1, "uint16": 2, "float16": 2, "float32": 4}
MAX_HEADER = 1 << 20
MAX_DIMS = 4
MAX_DEPTH = 32  # nesting of JSON arrays and objects: a header, a light map, a list of AO edits
CHUNK = 1 << 20  # bytes read at once


class ProtocolError(RuntimeError):
    """The stream does not hold a well-formed message. ``skip``: the buffer bytes that follow a refused header,
    where it declares them consistently enough to step over (None: unknown)."""

    def __init__(self, message: str, skip: int | None = None) -> None:
        super().__init__(message)
        self.skip = skip


class NestingError(ValueError):
    """JSON nested deeper than :data:`MAX_DEPTH` arrays and objects."""


def loads(text: str | bytes) -> Any:
    """JSON text as Python values; NestingError where it nests deeper than :data:`MAX_DEPTH` (a deep but
    well-formed text would otherwise exhaust the stack, here or in whatever reads the values),
    json.JSONDecodeError (or UnicodeDecodeError) where it is not JSON."""
    too_deep = f"JSON nested more than {MAX_DEPTH} arrays or objects deep"
    try:
        value = json.loads(text)
    except RecursionError:
        raise NestingError(too_deep) from None
    if _depth(value) > MAX_DEPTH:
        raise NestingError(too_deep)
    return value


def checked_number(value: Any, name: str, lo: float, hi: float, error: type[Exception]) -> float:
    """``value`` as a float if it is a finite number (not a bool) in [lo, hi]; else ``error`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise error(f"{name}: expected a number, got {value!r}")
    if not lo <= value <= hi:
        raise error(f"{name}: expected a number in [{lo:g}, {hi:g}], got {value!r}")
    return float(value)


def versioned(data: Any, fmt: str, version: int, reader: str, error: type[Exception]) -> dict:
    """``data`` checked to be a JSON object of format ``fmt`` and version ``version`` (the files the kit writes:
    light maps, a host's saved settings); else ``error`` naming the field and what ``reader`` reads."""
    if not isinstance(data, dict):
        raise error(f"expected a JSON object, got {type(data).__name__}")
    if data.get("format") != fmt:
        raise error(f"format: expected {fmt!r}, got {data.get('format')!r}")
    if data.get("version") != version:
        raise error(f"version: {reader} reads version {version}, got {data.get('version')!r}")
    return data


def _depth(value: Any) -> int:
    """How many arrays and objects deep ``value`` nests (iteratively: any depth)."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, level = stack.pop()
        children = item.values() if isinstance(item, dict) else item if isinstance(item, list) else None
        if children is not None:
            deepest = max(deepest, level)
            stack.extend((child, level + 1) for child in children)
    return deepest


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


def encode_header(header: dict, buffers: dict[str, Buffer] | None = None) -> bytes:
    """One message's header line, its ``buffers`` list made from ``buffers`` (their bytes follow it, in order)."""
    header = dict(header)
    header["buffers"] = [
        {"name": name, "dtype": b.dtype, "shape": list(b.shape), "nbytes": len(memoryview(b.data).cast("B"))}
        for name, b in (buffers or {}).items()
    ]
    return json.dumps(header, separators=(",", ":")).encode("utf-8") + b"\n"


def write_message(stream: IO[bytes], header: dict, buffers: dict[str, Buffer] | None = None) -> None:
    """Write one message and flush."""
    stream.write(encode_header(header, buffers))
    stream.writelines(memoryview(b.data).cast("B") for b in (buffers or {}).values())
    stream.flush()


def _read_exact(stream: IO[bytes], n: int) -> bytes:
    chunks, left = [], n
    while left:
        chunk = stream.read(min(left, CHUNK))
        if not chunk:
            raise EOFError(f"stream ended with {left} of {n} bytes unread")
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def skip(stream: IO[bytes], n: int) -> None:
    """Read and drop ``n`` bytes (a refused request's buffers) in bounded chunks."""
    left = n
    while left:
        chunk = stream.read(min(left, CHUNK))
        if not chunk:
            raise EOFError(f"stream ended with {left} of {n} bytes unread")
        left -= len(chunk)


class BufferSpec(NamedTuple):
    """One buffer as a header declares it, checked for consistency but not yet read."""

    name: str
    dtype: str
    shape: tuple[int, ...]
    nbytes: int


def _spec(entry: object) -> BufferSpec:
    """A header's buffer entry, checked: known dtype, at most MAX_DIMS sizes >= 0, ``nbytes`` that they need."""
    if not isinstance(entry, dict):
        raise ProtocolError(f"malformed buffer entry {entry!r}")
    name, dtype, shape, nbytes = (entry.get(k) for k in ("name", "dtype", "shape", "nbytes"))
    if not isinstance(name, str) or not isinstance(nbytes, int) or isinstance(nbytes, bool) or nbytes < 0:
        raise ProtocolError(f"malformed buffer entry {entry!r}: needs a name and nbytes >= 0")
    if dtype not in DTYPES:
        raise ProtocolError(f"buffer {name!r}: unsupported dtype {dtype!r}; use one of {sorted(DTYPES)}", nbytes)
    if (
        not isinstance(shape, list)
        or len(shape) > MAX_DIMS
        or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in shape)
    ):
        raise ProtocolError(f"buffer {name!r}: shape must be a list of at most {MAX_DIMS} sizes >= 0", nbytes)
    expected = DTYPES[dtype]
    for s in shape:
        expected *= s
    if expected != nbytes:
        raise ProtocolError(
            f"buffer {name!r} of shape {shape} {dtype} needs {expected} bytes, the header declares {nbytes}", nbytes
        )
    return BufferSpec(name, dtype, tuple(shape), nbytes)


def read_header(stream: IO[bytes]) -> tuple[dict, list[BufferSpec]]:
    """Read one message's header line and check its buffer entries, without reading the buffers.

    EOFError at a clean end of stream. A ProtocolError's ``skip`` is the number of buffer bytes that follow
    the header (the stream stays in step after :func:`skip`), or None where the header cannot say."""
    line = stream.readline(MAX_HEADER + 1)
    if not line:
        raise EOFError("stream closed")
    return parse_header(line)


def parse_header(line: bytes) -> tuple[dict, list[BufferSpec]]:
    """A header line (ending in a newline) as the header and its checked buffer entries (see :func:`read_header`)."""
    if not line.endswith(b"\n") or len(line) > MAX_HEADER + 1:
        raise ProtocolError("header line too long or truncated")
    try:
        header = loads(line)
    except NestingError as exc:
        raise ProtocolError(f"header: {exc}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ProtocolError(f"header is not JSON: {exc}") from None
    if not isinstance(header, dict):
        raise ProtocolError("header must be a JSON object")
    entries = header.pop("buffers", None) or []
    if not isinstance(entries, list):
        raise ProtocolError("header: buffers must be a list")
    sizes = [e.get("nbytes") if isinstance(e, dict) else None for e in entries]
    counts = [n for n in sizes if isinstance(n, int) and not isinstance(n, bool) and n >= 0]
    declared = sum(counts) if len(counts) == len(sizes) else None  # None unless every entry declares its nbytes
    try:
        specs = [_spec(e) for e in entries]
    except ProtocolError as exc:
        raise ProtocolError(str(exc), declared) from None
    if len({s.name for s in specs}) != len(specs):
        raise ProtocolError("buffers: each name may appear once", declared)
    return header, specs


def read_buffers(stream: IO[bytes], specs: list[BufferSpec]) -> dict[str, Buffer]:
    """Read the buffers a header declared."""
    return {s.name: Buffer(s.dtype, s.shape, _read_exact(stream, s.nbytes)) for s in specs}


def read_message(stream: IO[bytes]) -> tuple[dict, dict[str, Buffer]]:
    """Read one message; EOFError at a clean end of stream."""
    header, specs = read_header(stream)
    return header, read_buffers(stream, specs)


class MessageDecoder:
    """Sans-IO reading for event-driven clients (Krita's QProcess): :meth:`feed` takes bytes as they arrive and
    returns the messages they complete."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self._pending: tuple[dict, list[BufferSpec]] | None = None  # a parsed header waiting for its buffers

    def feed(self, data: bytes) -> list[tuple[dict, dict[str, Buffer]]]:
        self._buf += data
        out = []
        while True:
            if self._pending is None:
                end = self._buf.find(b"\n")
                if end < 0:
                    if len(self._buf) > MAX_HEADER:
                        raise ProtocolError("header line too long")
                    return out
                self._pending = parse_header(bytes(self._buf[: end + 1]))
                del self._buf[: end + 1]
            header, specs = self._pending
            if len(self._buf) < sum(s.nbytes for s in specs):
                return out
            buffers, pos = {}, 0
            with memoryview(self._buf) as view:  # one copy per buffer (a bytearray slice would make two)
                for spec in specs:
                    buffers[spec.name] = Buffer(spec.dtype, spec.shape, bytes(view[pos : pos + spec.nbytes]))
                    pos += spec.nbytes
            del self._buf[:pos]
            self._pending = None
            out.append((header, buffers))
