"""The package's structure: no import cycle, the layers import downwards only, modules stay small.

Imports are read from the source text (nothing is imported), at module level and inside functions and
``if TYPE_CHECKING:`` blocks alike, so a cycle cannot hide behind a local import.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "strokeopt"

#: Packages that compute (they return data); they never import what reports, measures or parses commands.
DOMAIN = ("io", "motion", "drive", "design", "contact", "servo", "linkage", "transmissions", "problem", "studies",
          "files")
#: The floors of docs/architecture.md: a module imports only from its own floor or below (the ground is 0).
FLOORS = {"errors": 0, "_casadi": 0, "_stdout": 0, "io": 0, "motion": 1, "drive": 2, "linkage": 2, "transmissions": 2,
          "contact": 3,
          "servo": 3, "design": 4, "problem": 5, "studies": 6, "files": 7, "report": 8, "cli": 9, "bench": 9,
          "__main__": 10}
#: Top-level names the domain must not import.
ABOVE_DOMAIN = ("report", "bench", "cli")
MAX_LINES = 500


def _name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _modules() -> dict[str, Path]:
    return {_name(p): p for p in sorted(PACKAGE.rglob("*.py")) if "__pycache__" not in p.parts}


def _imports(path: Path, modules: dict[str, Path]) -> list[tuple[str, int]]:
    """(imported module of the package, line) for every import in ``path``."""
    name = _name(path)
    is_pkg = path.name == "__init__.py"
    found = []

    def add(target: str, line: int) -> None:
        parts = target.split(".")
        while parts:
            candidate = ".".join(parts)
            if candidate in modules:
                if candidate != name:
                    found.append((candidate, line))
                return
            parts.pop()

    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                add(alias.name, node.lineno)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_pkg else name.split(".")[:-1]
                base = base[: len(base) - (node.level - 1)]
                base = ".".join(base + ([node.module] if node.module else []))
            else:
                base = node.module or ""
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                add(sub if sub in modules else base, node.lineno)
    return found


def _graph() -> dict[str, list[tuple[str, int]]]:
    modules = _modules()
    return {m: _imports(p, modules) for m, p in modules.items()}


def _cycles(graph: dict[str, list[tuple[str, int]]]) -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w, _ in graph.get(v, []):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                out.append(sorted(group))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def _subpackages() -> set[str]:
    return {_name(p) for p in PACKAGE.rglob("__init__.py") if p.parent != PACKAGE}


def test_no_import_cycle():
    # the top-level __init__ re-exports the public API and so imports everything; every other module,
    # subpackage __init__ files included, takes part in the search
    graph = {m: e for m, e in _graph().items() if m != "strokeopt"}
    cycles = _cycles(graph)
    assert not cycles, "import cycles: " + "; ".join(" <-> ".join(c) for c in cycles)


def test_cycle_search_finds_a_cycle():
    graph = {"a": [("b", 1)], "b": [("c", 2)], "c": [("a", 3)], "d": [("a", 4)]}
    assert _cycles(graph) == [["a", "b", "c"]]


def test_modules_import_concrete_modules_not_subpackages():
    # `from ..design import solve_design` would hide the real edge behind the package's __init__
    packages = _subpackages()
    bad = [f"{m} line {line} imports {t}" for m, edges in _graph().items() if m != "strokeopt"
           for t, line in edges if t in packages]
    assert not bad, "\n".join(bad)


def test_subpackage_inits_import_nothing():
    bad = [f"{m} imports {t}" for m, edges in _graph().items() if m in _subpackages() for t, _ in edges]
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("layer", DOMAIN)
def test_domain_never_imports_report_bench_or_cli(layer):
    above = tuple(f"strokeopt.{n}" for n in ABOVE_DOMAIN)
    bad = [f"{m} line {line} imports {t}" for m, edges in _graph().items() if m.startswith(f"strokeopt.{layer}")
           for t, line in edges if t == "strokeopt" or t.startswith(above)]
    assert not bad, "\n".join(bad)


def test_nothing_imports_the_command_line():
    bad = [m for m, edges in _graph().items() if any(t.startswith("strokeopt.cli") for t, _ in edges)
           and not m.startswith("strokeopt.cli") and m != "strokeopt.__main__"]
    assert not bad


def test_no_module_over_the_size_limit():
    big = {m: n for m, p in _modules().items() if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert not big, f"modules over {MAX_LINES} lines: {big}"


def _top(module: str) -> str:
    """The top-level name of a module of the package: ``strokeopt.design.solve`` -> ``design``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def test_every_package_has_a_floor():
    missing = sorted({_top(m) for m in _modules() if m != "strokeopt"} - set(FLOORS))
    assert not missing, f"packages without a floor in FLOORS (docs/architecture.md): {missing}"


def test_imports_point_down_the_floors():
    # no package cycle: each arrow goes to the importer's own floor or below (the public __init__ excepted)
    bad = [f"{m} line {line} imports {t} (floor {FLOORS[_top(t)]} above {FLOORS[_top(m)]})"
           for m, edges in _graph().items() if m != "strokeopt"
           for t, line in edges if t != "strokeopt" and FLOORS.get(_top(t), 0) > FLOORS.get(_top(m), 0)]
    assert not bad, "\n".join(bad)
