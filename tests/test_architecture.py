"""The import graph, walked from the source: layers, cycles, the host kit and declared dependencies."""

from __future__ import annotations

import ast
import re
import sys
import tomllib
from importlib.metadata import packages_distributions
from pathlib import Path

from ssn_engine.plugin_files import KIT_MODULES, KIT_PACKAGE

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("ssn_engine", "training", "plugin_krita", "plugin_gimp")
GIMP_DIR = ROOT / "plugin_gimp" / "ssn-shadow"  # loose modules, imported by name from their folder


def module_name(path: Path) -> str:
    if path.parent == GIMP_DIR:
        return f"plugin_gimp.{path.stem}"
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _kit_copy(path: Path) -> bool:
    """A file of a plug-in's installed copy of the host kit (written by a link install into the tree)."""
    return path.parts[len(ROOT.parts)].startswith("plugin_") and KIT_PACKAGE in path.parts


def source_modules() -> dict[str, Path]:
    files = [p for pkg in PACKAGES for p in (ROOT / pkg).rglob("*.py") if not _kit_copy(p)]
    return {module_name(p): p for p in files}


def imports(path: Path, name: str, known: dict[str, Path]) -> set[str]:
    """Every module ``path`` imports, at any depth of its code (deferred imports count), resolved to this
    project's modules where they are ours, else the top-level name."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.rsplit(".", node.level - 1)[0] if node.level > 1 else package
                stem = f"{base}.{node.module}" if node.module else base
            else:
                stem = node.module or ""
            submodules = [f"{stem}.{a.name}" for a in node.names if f"{stem}.{a.name}" in known]
            targets = submodules if len(submodules) == len(node.names) else [*submodules, stem]
        else:
            continue
        for target in targets:
            if path.parent == GIMP_DIR and f"plugin_gimp.{target.split('.')[0]}" in known:
                target = f"plugin_gimp.{target.split('.')[0]}"
            if target in known:
                found.add(target)
            elif not target.startswith(PACKAGES):
                found.add(target.split(".")[0])
    return found


def graph() -> dict[str, set[str]]:
    known = source_modules()
    return {name: imports(path, name, known) for name, path in known.items()}


def test_layers_engine_never_imports_plugins_or_training():
    for name, deps in graph().items():
        if name.startswith("ssn_engine"):
            bad = sorted(d for d in deps if d.startswith(("plugin_krita", "plugin_gimp", "training")))
            assert not bad, f"{name} imports {bad}"
        if name.startswith(("plugin_krita", "plugin_gimp")):
            bad = sorted(d for d in deps if d.startswith("training"))
            assert not bad, f"{name} imports {bad}"


def test_no_import_cycles():
    """No two modules import each other, directly or around a loop (a package's ``__init__`` that its own
    modules import for ``__version__`` is not an edge: Python runs it first anyway)."""
    g = graph()
    packages = {n for n, p in source_modules().items() if p.name == "__init__.py"}
    edges = {n: {d for d in deps if d in g and d not in packages and d != n} for n, deps in g.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    cycles: list[list[str]] = []

    def visit(node: str) -> None:  # Tarjan's strongly connected components
        index[node] = low[node] = len(index)
        stack.append(node)
        for dep in edges[node]:
            if dep not in index:
                visit(dep)
                low[node] = min(low[node], low[dep])
            elif dep in stack:
                low[node] = min(low[node], index[dep])
        if low[node] == index[node]:
            component = []
            while True:
                top = stack.pop()
                component.append(top)
                if top == node:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 5000))
    for node in sorted(edges):
        if node not in index:
            visit(node)
    assert not cycles, f"import cycles: {cycles}"


def test_host_kit_is_stdlib_only_and_closed():
    """The modules copied into both plug-ins import the standard library and each other, nothing else."""
    kit = {module_name(ROOT / "ssn_engine" / KIT_PACKAGE / m) for m in KIT_MODULES}
    g = graph()
    for name in kit:
        for dep in g[name]:
            if dep.startswith("ssn_engine"):
                assert dep in kit, f"{name} imports {dep}, which the plug-ins do not carry"
            else:
                assert dep in sys.stdlib_module_names or dep == "__future__", f"{name} imports {dep}"


# the hosts' own modules (Krita ships plugin_importer), and the docker as Krita imports it (the benchmark's in-Krita
# driver, plugin_krita/bench_driver.py, drives the installed ssn_shadow)
HOSTS = {"krita", "PyQt5", "gi", "plugin_importer", "ssn_shadow"}


def requirement_names(requirements: list[str]) -> set[str]:
    """The distribution names of requirement strings, normalised (lower case, "-")."""
    out = set()
    for req in requirements:
        for stop in "<>=![ ;":
            req = req.split(stop)[0]
        out.add(req.strip().lower().replace("_", "-"))
    return out


def declared() -> tuple[set[str], dict[str, set[str]]]:
    """pyproject.toml's runtime dependencies and its extras, as distribution names."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    extras = {k: requirement_names(v) for k, v in project["optional-dependencies"].items()}
    return requirement_names(project["dependencies"]), extras


def third_party(deps: set[str]) -> set[str]:
    """The top-level third-party modules among ``deps``."""
    return {d for d in deps if "." not in d and d not in sys.stdlib_module_names and d not in ("__future__", *PACKAGES)}


def imported_by_tests() -> set[str]:
    """The third-party and local top-level modules the tests import, less the tests' own modules."""
    local = {p.stem for p in (ROOT / "tests").rglob("*.py")} | {p.stem for p in GIMP_DIR.glob("*.py")}
    found = {d for p in (ROOT / "tests").rglob("*.py") for d in imports(p, p.stem, {})}
    return third_party(found) - local - set(PACKAGES)


def skipped_without() -> set[str]:
    """The modules a test skips without (``pytest.importorskip("name")``)."""
    found = set()
    for path in (ROOT / "tests").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr == "importorskip"
                and node.args
                and isinstance(node.args[0], ast.Constant)
            ):
                found.add(str(node.args[0].value).split(".")[0])
    return found


def test_the_readme_test_command_installs_what_the_checks_import():
    """A fresh machine runs the README's test command: the extras it installs hold every third-party module that
    pyright resolves (the engine, training, the plug-ins) and that the tests import or skip without, and CI runs
    that very line in a fresh virtual environment of its own (no system site-packages), so that a package
    installed by hand on a developer's machine cannot hide a missing install step."""
    commands = re.findall(
        r'^pip install -e "\.\[([a-z,]+)\]" && python -m pytest$', (ROOT / "README.md").read_text(), re.M
    )
    assert len(commands) == 1, "the README names one test command"
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert f'pip install -e ".[{commands[0]}]" && python -m pytest' in ci, ".ci/run runs the README's test command"
    venv = [line for line in ci if "-m venv" in line]
    assert venv and not any("system-site-packages" in line for line in venv), ".ci/run makes a fresh environment"
    runtime, extras = declared()
    installed = runtime.union(*(extras[name] for name in commands[0].split(",")), {"ssn-shadow"})
    dists = packages_distributions()
    g = graph()
    checked = {d for ds in g.values() for d in ds} | imported_by_tests() | skipped_without()
    for module in sorted(third_party(checked) - HOSTS - {"tools", KIT_PACKAGE}):
        names = {d.lower().replace("_", "-") for d in dists.get(module, [module])}
        assert names & installed, f"{module} ({sorted(names)}) is imported but the README's test command omits it"


def test_every_imported_dependency_is_declared():
    """Each third-party import of the engine is a dependency, of training one of the train extra (Mitsuba: the
    reference extra), of the tests one of the dev extra; the plug-ins import only their hosts' modules."""
    runtime, extras = declared()
    dists = packages_distributions()
    g = graph()
    tests = imported_by_tests()
    for scope, allowed, deps in (
        ("ssn_engine", runtime, {d for n, ds in g.items() if n.startswith("ssn_engine") for d in ds}),
        (
            "training",
            runtime | extras["train"] | extras["reference"],
            {d for n, ds in g.items() if n.startswith("training") for d in ds},
        ),
        ("tests", runtime | extras["train"] | extras["dev"], tests),
    ):
        for module in sorted(third_party(deps) - HOSTS - {"tools", KIT_PACKAGE}):
            names = {d.lower().replace("_", "-") for d in dists.get(module, [module])}
            assert names & (allowed | {"ssn-shadow"}), (
                f"{scope} imports {module} ({sorted(names)}), not declared for it"
            )
    plugin_deps = {d for n, ds in g.items() if n.startswith(("plugin_krita", "plugin_gimp")) for d in ds}
    plugin_third = third_party(plugin_deps) - HOSTS - {KIT_PACKAGE}
    assert not plugin_third, f"the plug-ins import {sorted(plugin_third)}"
