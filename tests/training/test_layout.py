"""training/ as a library and thin commands: no module imports a command, every command parses its arguments in
``parse_args``, and imports sit at module level except for the optional heavy dependencies named here."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TRAINING = ROOT / "training"
COMMANDS = (
    "benchmark_bases",
    "camera_estimator",
    "evaluate",
    "export",
    "heights",
    "make_dataset",
    "onnx_weights",
    "train",
)
# where an import inside a function is the point: anny, roma and torch build people only when asked, Mitsuba and
# drjit are the reference extra, numba has a numpy fallback
LATE_IMPORTS = {
    "training/benchmark_bases.py": {"anny", "training.data.humans", "drjit", "mitsuba"},
    "training/canvas_eval/mitsuba_check.py": {"drjit", "mitsuba"},
    "training/data/humans.py": {"anny", "roma", "torch"},
    "training/data/spans.py": {"numba"},
}


def _modules() -> dict[str, ast.Module]:
    return {str(p.relative_to(ROOT)): ast.parse(p.read_text()) for p in sorted(TRAINING.rglob("*.py"))}


def _imported(node: ast.Import | ast.ImportFrom, path: str) -> list[str]:
    """The absolute names an import statement in the module at ``path`` brings in."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    package = Path(path).with_suffix("").parts[: -node.level] if node.level else ()
    base = ".".join([*package, *([node.module] if node.module else [])])
    return [base] + [f"{base}.{a.name}" for a in node.names]


def test_no_module_imports_a_command():
    commands = {f"training.{c}" for c in COMMANDS}
    for path, tree in _modules().items():
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)):
                bad = commands & set(_imported(node, path))
                assert not bad, f"{path} imports the command {bad}: move what it needs into a library module"


def test_every_command_parses_its_arguments_in_parse_args():
    for name in COMMANDS:
        tree = ast.parse((TRAINING / f"{name}.py").read_text())
        functions = {n.name for n in tree.body if isinstance(n, ast.FunctionDef)}
        assert {"main", "parse_args"} <= functions, name


def test_imports_sit_at_module_level():
    for path, tree in _modules().items():
        late = set()
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                for inner in ast.walk(node):
                    if isinstance(inner, (ast.Import, ast.ImportFrom)):
                        late.update(
                            _imported(inner, path)[:1] if isinstance(inner, ast.ImportFrom) else _imported(inner, path)
                        )
        assert late <= LATE_IMPORTS.get(path, set()), f"{path}: imports inside functions {sorted(late)}"
