"""The layout's rules, checked from the source (docs/architecture.md):

- no import cycles between the core's modules, counting imports inside functions;
- the core (``framework/rotorid``) never imports a plugin package;
- the report (figures and HTML) is a leaf: only the command line imports it.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CORE = ROOT / "framework" / "rotorid"
PLUGIN_PACKAGES = sorted(p.name for p in (ROOT / "plugins").iterdir()
                         if (p / "__init__.py").is_file())


def module_name(path: Path) -> str:
    parts = list(path.relative_to(CORE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES = {module_name(p): p for p in CORE.rglob("*.py")}


def imported_modules(path: Path) -> set[str]:
    """Every module a source file imports, at any depth of its code."""
    found = set()
    package = module_name(path) if path.name == "__init__.py" else module_name(path).rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            for alias in node.names:
                found.add(f"{base}.{alias.name}" if f"{base}.{alias.name}" in MODULES else base)
    return found


GRAPH = {name: {m for m in imported_modules(path) if m in MODULES and m != name}
         for name, path in MODULES.items()}


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's components with more than one module (the import cycles)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(graph[node]):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def test_the_core_has_no_import_cycles():
    # The package facade (rotorid/__init__) re-exports the public API; modules below it import
    # their neighbours directly, so it takes part in no cycle either.
    assert strongly_connected(GRAPH) == []


def test_the_core_imports_no_plugin_package():
    offenders = {name: sorted(m for m in imported_modules(path)
                              if m.split(".")[0] in PLUGIN_PACKAGES)
                 for name, path in MODULES.items()}
    assert {k: v for k, v in offenders.items() if v} == {}


def test_the_report_is_a_leaf():
    importers = {name for name, targets in GRAPH.items()
                 if any(t == "rotorid.report" or t.startswith("rotorid.report.") for t in targets)
                 and not name.startswith(("rotorid.report", "rotorid.cli"))}
    assert importers == set()


def test_the_cycle_finder_finds_a_cycle():
    assert strongly_connected({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [
        ["a", "b", "c"]]
