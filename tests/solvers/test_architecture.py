"""The shape of ``lumped.solvers`` (issue 26): the layers run one way, no import cycle,
no module reaches for another module's private name, and no module is over 400 lines.

The layers are an import-linter contract in ``pyproject.toml`` (``[tool.importlinter]``);
this test runs it, so the README's test command checks it."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / "src"
SOLVERS = SRC / "lumped" / "solvers"
MAX_LINES = 400


def _module(path: Path) -> tuple[str, bool]:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    is_pkg = parts[-1] == "__init__"
    return ".".join(parts[:-1] if is_pkg else parts), is_pkg


def _imports(path: Path):
    """``(target module, imported name)`` of every ``from ... import`` in ``path``,
    relative imports resolved; function-level imports included."""
    mod, is_pkg = _module(path)
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = mod.split(".") if is_pkg else mod.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            for alias in node.names:
                yield target, alias.name


def test_the_solver_layers_hold():
    importlinter_cli = pytest.importorskip("importlinter.cli")
    assert importlinter_cli.lint_imports(config_filename=str(SRC.parent / "pyproject.toml"),
                                         no_cache=True) == 0


def test_no_import_cycle_among_the_solver_modules():
    """No module of ``lumped.solvers`` reaches itself through its imports (function-level
    imports count; the package's own ``__init__`` re-exports are left out)."""
    grimp = pytest.importorskip("grimp")
    graph = grimp.build_graph("lumped", cache_dir=None)
    inside = {m for m in graph.modules if m.startswith("lumped.solvers.")}
    packages = {m for m in inside if graph.find_children(m)}
    state: dict[str, int] = {}
    cycles: list[list[str]] = []

    def visit(m: str, path: list[str]) -> None:
        state[m] = 1
        path.append(m)
        for n in sorted(graph.find_modules_directly_imported_by(m)):
            if n not in inside or n in packages:
                continue
            if state.get(n) == 1:
                cycles.append(path[path.index(n):] + [n])
            elif n not in state:
                visit(n, path)
        path.pop()
        state[m] = 2

    for m in sorted(inside - packages):
        if m not in state:
            visit(m, [])
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c) for c in cycles)


def test_no_module_imports_another_modules_private_name():
    bad = [f"{_module(p)[0]}: {target}.{name}"
           for p in sorted((SRC / "lumped").rglob("*.py"))
           for target, name in _imports(p)
           if target.startswith("lumped") and name.startswith("_")
           and not name.startswith("__")]
    assert not bad, "private names imported across modules:\n" + "\n".join(bad)


def test_no_solver_module_is_over_the_limit():
    long = {str(p.relative_to(SRC)): n for p in sorted(SOLVERS.rglob("*.py"))
            if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not long, f"modules over {MAX_LINES} lines: {long}"


def test_a_reference_never_imports_its_compiled_twin():
    twins = {p.with_name(p.stem.removesuffix("_jit") + ".py"): _module(p)[0]
             for p in SOLVERS.rglob("*_jit.py")}
    bad = [f"{_module(ref)[0]} imports {twin}" for ref, twin in twins.items()
           if ref.exists() and any(t == twin or f"{t}.{n}" == twin for t, n in _imports(ref))]
    assert not bad, "\n".join(bad)
