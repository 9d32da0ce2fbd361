"""Write docs/bad_input.md: what the CLI and the worker answer to each bad input, as they answer it now.

Every CLI case runs ``ssn_engine.cli.main`` in a fresh folder and records the exit status, the first line of
stderr and whether every file in the folder is byte-identical afterwards; every worker case feeds one request
to :class:`ssn_engine.worker.Worker` over a byte stream, then a ``hello`` that must still be answered; the
loopback cases send a new connection's first bytes to :func:`ssn_engine.loopback.authenticate` over a socket pair.

usage: python tools/bad_input_table.py [--out docs/bad_input.md]
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import hashlib
import io
import json
import os
import socket
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image

from ssn_engine import cli
from ssn_engine.loopback import authenticate
from ssn_engine.methods import load_method
from ssn_engine.host_kit.protocol import read_message
from ssn_engine.worker import Worker

W, H = 120, 90


def _cutout(alpha: bool = True, opaque: bool = False) -> Image.Image:
    rgba = np.zeros((H, W, 4), np.uint8)
    rgba[..., :3] = (200, 120, 40)
    rgba[20:80, 50:70, 3] = 255
    if opaque:
        rgba[..., 3] = 255
    return Image.fromarray(rgba if alpha else rgba[..., :3])


def _prepare(folder: Path) -> None:
    _cutout().save(folder / "cutout.png")
    _cutout(alpha=False).save(folder / "photo.png")
    _cutout(alpha=False).save(folder / "photo.jpg")
    _cutout(opaque=True).save(folder / "opaque.png")
    Image.fromarray(np.zeros((H, W, 4), np.uint8)).save(folder / "empty.png")
    Image.fromarray(np.full((10, 10, 3), 200, np.uint8)).save(folder / "small_bg.png")
    Image.fromarray(np.full((H, W, 3), 200, np.uint8)).save(folder / "bg.png")
    (folder / "notes.png").write_text("not an image")
    (folder / "truncated.png").write_bytes((folder / "cutout.png").read_bytes()[:60])
    (folder / "broken.json").write_text("{broken")
    (folder / "nested.json").write_text("[" * 200_000 + "]" * 200_000)
    (folder / "zero.png").write_bytes(b"")
    (folder / "locked.png").write_bytes(b"the user's read-only layer")
    (folder / "locked.png").chmod(0o444)
    (folder / "far.json").write_text(
        json.dumps(
            {"format": "ssn-shadow-elm", "version": 1, "lights": [{"u": 2, "v": 0.5, "softness": 0.01, "intensity": 1}]}
        )
    )
    (folder / "dark.json").write_text(json.dumps({"format": "ssn-shadow-elm", "version": 1, "lights": []}))
    (folder / "edits.json").write_text(json.dumps({"op": "grow"}))
    (folder / "layer.png").write_bytes(b"the user's old layer")
    os.link(folder / "cutout.png", folder / "hardlink.png")


CLI_CASES = [
    ("cutout file missing", ["render", "nope.png", "--layer", "out.png"]),
    ("a text file named .png", ["render", "notes.png", "--layer", "out.png"]),
    ("truncated PNG", ["render", "truncated.png", "--layer", "out.png"]),
    ("empty (0-byte) file", ["render", "zero.png", "--layer", "out.png"]),
    ("RGB PNG (no alpha)", ["render", "photo.png", "--layer", "out.png"]),
    ("JPEG", ["render", "photo.jpg", "--layer", "out.png"]),
    ("RGBA opaque everywhere", ["render", "opaque.png", "--layer", "out.png"]),
    ("fully transparent cutout", ["render", "empty.png", "--layer", "out.png"]),
    ("light map without lights", ["render", "cutout.png", "--layer", "out.png", "--light-map", "dark.json"]),
    ("`--layer` is the cutout", ["render", "cutout.png", "--layer", "cutout.png"]),
    ("`--layer` is a hard link to the cutout", ["render", "cutout.png", "--layer", "hardlink.png"]),
    ("`--composite` is the background", ["render", "cutout.png", "--composite", "bg.png", "--background", "bg.png"]),
    ("`--layer` and `--composite` the same path", ["render", "cutout.png", "--layer", "o.png", "--composite", "o.png"]),
    ("output folder missing", ["render", "cutout.png", "--layer", "layer.png", "--composite", "no/c.png"]),
    ("`--layer` is a read-only file", ["render", "cutout.png", "--layer", "locked.png"]),
    ("`--layer` ends with a slash", ["render", "cutout.png", "--layer", "layer.png/"]),
    ("`--background` without `--composite`", ["render", "cutout.png", "--layer", "out.png", "--background", "bg.png"]),
    (
        "background of another size",
        ["render", "cutout.png", "--layer", "layer.png", "--composite", "c.png", "--background", "small_bg.png"],
    ),
    ("background not an image", ["render", "cutout.png", "--composite", "c.png", "--background", "notes.png"]),
    ("light map not JSON", ["render", "cutout.png", "--layer", "out.png", "--light-map", "broken.json"]),
    ("light outside the map", ["render", "cutout.png", "--layer", "out.png", "--light-map", "far.json"]),
    ("light map nested 200,000 deep", ["render", "cutout.png", "--layer", "out.png", "--light-map", "nested.json"]),
    ("AO edits not a list", ["render", "cutout.png", "--layer", "out.png", "--ao-edits", "edits.json"]),
    ("AO edits nested 200,000 deep", ["render", "cutout.png", "--layer", "out.png", "--ao-edits", "nested.json"]),
    ("image above `--max-megapixels`", ["render", "cutout.png", "--layer", "out.png", "--max-megapixels", "0.01"]),
    ("`--fov` without `--horizon`", ["render", "cutout.png", "--layer", "out.png", "--fov", "40"]),
    ("`--horizon nan`", ["render", "cutout.png", "--layer", "out.png", "--horizon", "nan"]),
    ("`--horizon` a billion rows down", ["render", "cutout.png", "--layer", "out.png", "--horizon", "1e9"]),
    ("`demo --save-samples` folder missing", ["demo", "--out", "d.png", "--save-samples", "nowhere"]),
    ("disk full while writing (simulated)", ["render", "cutout.png", "--layer", "layer.png"]),
]


def _digest(folder: Path) -> dict[str, str]:
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir()) if p.is_file()}


@contextlib.contextmanager
def _full_disk():
    real = Image.Image.save

    def save(self, fp, *args, **kwargs):
        fp.write(b"\x89PNG")
        raise OSError(errno.ENOSPC, "No space left on device")

    Image.Image.save = save
    try:
        yield
    finally:
        Image.Image.save = real


def cli_rows() -> list[tuple[str, str, str, str]]:
    rows = []
    for label, argv in CLI_CASES:
        with tempfile.TemporaryDirectory() as tmp:
            folder = Path(tmp)
            _prepare(folder)
            before = _digest(folder)
            err = io.StringIO()
            cwd = os.getcwd()
            os.chdir(folder)
            try:
                with (
                    contextlib.redirect_stderr(err),
                    contextlib.redirect_stdout(io.StringIO()),
                    _full_disk() if "disk full" in label else contextlib.nullcontext(),
                ):
                    try:
                        code = cli.main(argv + ["--method", "geometric"])
                    except SystemExit as exc:  # argparse's usage errors
                        code = exc.code
            finally:
                os.chdir(cwd)
            after = _digest(folder)
            unchanged = all(after.get(name) == digest for name, digest in before.items()) and set(after) == set(before)
            message = err.getvalue().strip().splitlines()[-1] if err.getvalue().strip() else ""
            rows.append((label, str(code), message, "yes" if unchanged else "**no**"))
    return rows


def _message(header: dict, payload: bytes = b"") -> bytes:
    return json.dumps(header).encode() + b"\n" + payload


def worker_rows() -> list[tuple[str, str, str, str]]:
    worker = Worker(load_method("geometric"))
    alpha = np.zeros((60, 80), np.uint8)
    alpha[10:50, 30:40] = 255

    def entry(shape, dtype="uint8", nbytes=None, name="alpha"):
        size = int(np.prod(shape)) * np.dtype(dtype).itemsize if nbytes is None else nbytes
        return {"name": name, "dtype": dtype, "shape": list(shape), "nbytes": size}

    setup = _message({"id": 0, "cmd": "set_cutout", "buffers": [entry(alpha.shape)]}, alpha.tobytes())
    cases = [
        ("a line that is not JSON", b"hello world\n", None),
        ("a line of 200,000 `[` then 200,000 `]`", b"[" * 200_000 + b"]" * 200_000 + b"\n", None),
        ("unknown command", _message({"id": 1, "cmd": "launch"}), None),
        (
            "unknown dtype",
            _message({"id": 1, "cmd": "set_cutout", "buffers": [entry((2, 2), "int64", 32)]}, bytes(32)),
            None,
        ),
        (
            "`nbytes` that the shape does not need",
            _message({"id": 1, "cmd": "set_cutout", "buffers": [entry((2, 2), nbytes=5)]}, bytes(5)),
            None,
        ),
        (
            "a header declaring a 10 GB buffer (never sent)",
            _message({"id": 1, "cmd": "set_cutout", "buffers": [entry((100000, 100000))]}),
            None,
        ),
        (
            "a canvas above 32768 pixels a side",
            _message({"id": 1, "cmd": "set_cutout", "buffers": [entry((1, 40000))]}, bytes(40000)),
            None,
        ),
        (
            "a buffer the command does not take",
            _message({"id": 1, "cmd": "render", "buffers": [entry((2, 2), name="layer")]}, bytes(4)),
            None,
        ),
        ("empty alpha", _message({"id": 1, "cmd": "set_cutout", "buffers": [entry((4, 4))]}, bytes(16)), None),
        (
            "a float alpha holding -1 and inf",
            _message(
                {"id": 1, "cmd": "set_cutout", "buffers": [entry((1, 2), "float32")]},
                np.array([[-1, np.inf]], np.float32).tobytes(),
            ),
            None,
        ),
        ("a cutout id that is a list", _message({"id": 1, "cmd": "get_ao", "cutout": [1]}), None),
        ("unknown cutout", _message({"id": 1, "cmd": "render", "cutout": "c999", "preset": "softbox"}), None),
        (
            "light map with a light outside the map",
            _message(
                {
                    "id": 1,
                    "cmd": "render",
                    "cutout": "c1",
                    "light_map": json.loads(
                        '{"format": "ssn-shadow-elm", "version": 1, "lights": [{"u": 2, "v": 0.5, "softness": 0.01, '
                        '"intensity": 1}]}'
                    ),
                }
            ),
            "setup",
        ),
        (
            "light map without lights",
            _message(
                {
                    "id": 1,
                    "cmd": "render",
                    "cutout": "c1",
                    "light_map": {"format": "ssn-shadow-elm", "version": 1, "lights": []},
                }
            ),
            "setup",
        ),
        (
            "AO edit with an unknown op",
            _message({"id": 1, "cmd": "edit_ao", "cutout": "c1", "edits": [{"op": "blur"}]}),
            "setup",
        ),
        (
            "camera with a field of view of 0",
            _message(
                {"id": 1, "cmd": "set_cutout", "camera": {"horizon": 10, "fov": 0}, "buffers": [entry(alpha.shape)]},
                alpha.tobytes(),
            ),
            None,
        ),
    ]
    rows = []
    for label, data, mode in cases:
        worker.sessions.clear()
        worker._ids = iter(range(1, 10**6))
        stream = (setup if mode == "setup" else b"") + data + _message({"id": 99, "cmd": "hello"})
        writer = io.BytesIO()
        worker.serve(io.BytesIO(stream), writer)
        writer.seek(0)
        replies = []
        with contextlib.suppress(EOFError):
            while True:
                replies.append(read_message(writer)[0])
        reply = replies[1] if mode == "setup" else replies[0]
        if reply.get("ok"):
            answer, message = "ok, 0 x 0 layer", f"no_shadow: {reply.get('no_shadow')}"
        else:
            answer, message = reply["error"]["type"], reply["error"]["message"]
        usable = replies[-1].get("id") == 99 and replies[-1].get("ok")
        rows.append((label, answer, message, "yes" if usable else "no (connection closed)"))
    loopback_cases = [
        ("loopback: a request before `auth`", _message({"id": 1, "cmd": "hello"})),
        ("loopback: garbage before `auth`", b"garbage\n"),
        ("loopback: `auth` with a wrong token", _message({"id": 1, "cmd": "auth", "token": "guess"})),
    ]
    for label, data in loopback_cases:
        ours, theirs = socket.socketpair()
        with ours, theirs:
            theirs.sendall(data)
            theirs.shutdown(socket.SHUT_WR)
            admitted = authenticate(ours, "secret")
            reply = json.loads(theirs.makefile("rb").readline())
        error = reply.get("error", {})
        rows.append((label, error.get("type", "ok"), error.get("message", ""), "yes" if admitted else "no (closed)"))
    return rows


def table(header: tuple[str, ...], rows: list[tuple[str, ...]]) -> str:
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(cell.replace("|", "\\|") for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="docs/bad_input.md")
    args = p.parse_args(argv)
    text = f"""# Bad input: what the CLI and the worker answer

Generated by `python tools/bad_input_table.py` from the current code (each case run as written, with the
geometric method); the messages are the program's own. Exit status: 0 written, 1 model error, 2 bad input,
3 no visible shadow (nothing written). "Your files unchanged" compares every file in the case's folder
byte for byte before and after.

## `ssn-shadow render` / `demo`

{table(("input", "exit", "message (stderr)", "your files unchanged"), cli_rows())}

## The worker (`ssn-shadow serve`; docs/protocol.md)

Each request is followed by a `hello` on the same stream; "still serving" says whether it was answered.

{table(("request", "reply", "message", "still serving"), worker_rows())}
"""
    Path(args.out).write_text(text)
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
