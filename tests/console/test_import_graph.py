"""No import cycle among the project's modules (console/ and plugins/), imports inside
functions counted: a cycle closed by a function-local import is still a cycle, it only
moves the failure from import time to the first call. A local import may keep a hardware
or heavy third-party library lazy; a local import of a project module is an edge like any
other. Only ``if TYPE_CHECKING:`` imports are left out: they never run.

``KNOWN`` lists the cycles left in areas still being reworked; it may only shrink (a
second test fails when an entry no longer is a cycle, so that it is removed)."""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("console", "plugins")

#: Cycles (strongly connected components) that exist today, each a set of modules that
#: import one another. Remove an entry when its cycle is broken; never add one.
KNOWN: tuple[frozenset[str], ...] = ()


def module_files(root: Path = ROOT) -> dict[str, Path]:
    """The project's modules by dotted name (a package by its own name)."""
    mods = {}
    for top in PACKAGES:
        for p in sorted((root / top).rglob("*.py")):
            parts = p.relative_to(root).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            mods[".".join(parts)] = p
    return mods


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def imports(tree: ast.AST) -> Iterator[tuple[ast.Import | ast.ImportFrom, bool]]:
    """Every import at any depth outside ``if TYPE_CHECKING:``, with whether it sits
    inside a function."""
    todo: list[tuple[ast.AST, bool]] = [(tree, False)]
    while todo:
        node, local = todo.pop()
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            todo.extend((n, local) for n in node.orelse)
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node, local
        inner = local or isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
        todo.extend((n, inner) for n in ast.iter_child_nodes(node))


def targets(node: ast.Import | ast.ImportFrom, package: str, mods: dict[str, Path]) -> set[str]:
    """The project modules one import statement loads (relative imports resolved against
    ``package``; ``from pkg import mod`` is the module, ``from mod import name`` the
    module)."""
    if isinstance(node, ast.Import):
        return {a.name for a in node.names if a.name in mods}
    base = node.module or ""
    if node.level:
        up = package.split(".")[: len(package.split(".")) - node.level + 1]
        base = ".".join(up + ([base] if base else []))
    subs = {f"{base}.{a.name}" for a in node.names if f"{base}.{a.name}" in mods}
    names = subs if subs and len(subs) == len(node.names) else {base, *subs}
    return {t for t in names if t in mods}


def import_graph(root: Path = ROOT) -> tuple[dict[str, set[str]], int]:
    """module -> the project modules it imports; and how many import statements inside
    functions load a project module."""
    mods = module_files(root)
    graph: dict[str, set[str]] = {}
    local_count = 0
    for name, path in mods.items():
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        edges: set[str] = set()
        for node, local in imports(ast.parse(path.read_text(encoding="utf-8"))):
            found = targets(node, package, mods) - {name}
            local_count += bool(local and found)
            edges |= found
        graph[name] = edges
    return graph, local_count


def cycles(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """The strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[frozenset[str]] = []
    for start in sorted(graph):
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph.get(w, ())))))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = set()
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.add(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(frozenset(comp))
    return out


def _show(graph: dict[str, set[str]], comp: frozenset[str]) -> str:
    edges = [f"  {m} -> {t}" for m in sorted(comp) for t in sorted(graph[m] & comp)]
    return "\n".join(edges)


def test_no_import_cycle_among_the_projects_modules():
    graph, _ = import_graph()
    new = [c for c in cycles(graph) if c not in KNOWN]
    assert not new, (
        "import cycles (function-local imports count; move the shared piece down into a "
        "module of its own):\n" + "\n\n".join(_show(graph, c) for c in new)
    )


def test_the_known_cycles_are_still_cycles():
    """KNOWN only shrinks: a cycle that was broken leaves the list."""
    gone = [sorted(c) for c in KNOWN if c not in cycles(import_graph()[0])]
    assert not gone, f"no longer a cycle, remove from KNOWN in {__file__}: {gone}"


def test_the_graph_counts_local_and_relative_imports(tmp_path):
    """A cycle closed inside a function is found; a TYPE_CHECKING import is no edge; a
    relative import is resolved; a local import of a third-party library is no edge."""
    pkg = tmp_path / "plugins" / "demo"
    pkg.mkdir(parents=True)
    (tmp_path / "console").mkdir()
    (tmp_path / "console" / "__init__.py").write_text("")
    (tmp_path / "plugins" / "__init__.py").write_text("")
    (pkg / "__init__.py").write_text("from . import run\n")
    (pkg / "run.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from .cam import Cam\n"
        "def f():\n    from plugins.demo.cam import child\n    import numpy\n"
    )
    (pkg / "cam.py").write_text("def child():\n    from .run import f\n")
    graph, local = import_graph(tmp_path)
    assert graph["plugins.demo"] == {"plugins.demo.run"}
    assert graph["plugins.demo.run"] == {"plugins.demo.cam"}
    assert graph["plugins.demo.cam"] == {"plugins.demo.run"}
    assert local == 2
    assert cycles(graph) == [frozenset({"plugins.demo.run", "plugins.demo.cam"})]
