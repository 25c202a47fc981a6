"""The shape of the code: modules that import each other in a circle, and
source files grown past one idea, are what make a codebase hard to change;
these tests keep both out."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "python" / "mcsample"
#: The longest a source file may be (tests beside the code excluded).
MAX_LINES = 650

pytestmark = pytest.mark.skipif(not PACKAGE.exists(), reason="needs the source tree")


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _runtime_imports(tree: ast.AST) -> list[ast.AST]:
    """Import statements that run (anywhere, also inside functions), leaving
    out ``if TYPE_CHECKING:`` blocks."""
    found = []

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            return
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            found.append(node)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return found


def _python_graph() -> dict[str, set[str]]:
    modules = {_module_name(p): p for p in PACKAGE.rglob("*.py")}
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        deps = set()
        for node in _runtime_imports(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                base = package.split(".")[:len(package.split(".")) - (node.level - 1)] \
                    if node.level else []
                module = ".".join(base + ([node.module] if node.module else []))
                targets = [f"{module}.{a.name}" if f"{module}.{a.name}" in modules else module
                           for a in node.names]
            deps.update(t for t in targets if t in modules and t != name)
        graph[name] = deps
    return graph


def _rust_python_graph() -> dict[str, set[str]]:
    """Which files of the binding layer (src/python) use which others."""
    files = {p.stem if p.name != "mod.rs" else p.parent.name: p
             for p in (ROOT / "src" / "python").rglob("*.rs")}
    graph = {}
    for name, path in files.items():
        code = "\n".join(line.split("//")[0] for line in path.read_text().splitlines())
        used = set(re.findall(r"(?:super|crate::python)::(\w+)", code))
        graph[name] = {u for u in used if u in files and u != name}
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    path: list[str] = []

    def visit(u: str) -> list[str] | None:
        state[u] = 1
        path.append(u)
        for v in sorted(graph[u]):
            if state.get(v) == 1:
                return path[path.index(v):] + [v]
            if v not in state and (found := visit(v)):
                return found
        path.pop()
        state[u] = 2
        return None

    for u in sorted(graph):
        if u not in state and (found := visit(u)):
            return found
    return None


def test_no_import_cycle_in_the_python_package():
    cycle = _cycle(_python_graph())
    assert cycle is None, " -> ".join(cycle)


def test_no_cycle_between_the_binding_files():
    cycle = _cycle(_rust_python_graph())
    assert cycle is None, " -> ".join(cycle)


def test_no_source_file_grows_past_one_idea():
    sources = [p for p in (ROOT / "src").rglob("*.rs") if p.name != "tests.rs"]
    sources += list(PACKAGE.rglob("*.py"))
    long = {str(p.relative_to(ROOT)): n for p in sources
            if (n := len(p.read_text().splitlines())) > MAX_LINES}
    assert not long, f"files over {MAX_LINES} lines: {long}"
