"""console/ in layers without cycles: types -> profile -> safety -> kernel -> runtime ->
session -> tui -> cli, the benchmarks beside cli at the top. A module imports its own layer or lower ones,
function-local imports included (only ``if TYPE_CHECKING:`` imports are left out: they never
run), and no chain of imports comes back to where it started."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

LAYERS = ("types", "profile", "safety", "kernel", "runtime", "session", "tui", "cli")

#: folder -> layer: every console module sits in a folder, and the folder says its layer
#: (``console`` alone is the package's ``__init__``). The longest match wins, so the
#: plugin API's modules can sit at the layer of what each re-exports.
LAYER_OF: dict[str, str] = {
    "console": "types",
    "console.core": "types",  # types, errors, words, contracts, hook specs, option checks
    "console.files": "types",  # paths, atomic writes, bounded reads, cache files, map format
    "console.signals": "types",  # waveforms, the signal language, stimuli, live streams
    "console.config": "profile",  # the profile, the plugin manager, per-profile files
    "console.safety": "safety",  # the gate, its limits, the e-stop
    "console.plugin_api": "safety",  # the plugin API's core: re-exports up to safety
    "console.kernel": "kernel",  # the outputs process of a table, and its clients' side
    "console.runtime": "runtime",  # loops, devices, the projector process, the watchdog
    "console.session": "session",  # what the console does, with no Textual
    "console.plugin_api.runtime": "session",  # the plugin API: runtime, kernel client, events
    "console.tui": "tui",  # the Textual screens
    "console.plugin_api.tui": "tui",  # the plugin API: the Textual helpers panels use
    "console.cli": "cli",  # `haptable`: entry (estop/reset before anything heavy), commands
    "console.benchmarks": "cli",  # the top, beside the CLI that registers them
}


def module_files(root: Path = ROOT) -> dict[str, Path]:
    """console/'s modules by dotted name (a package by its own name)."""
    mods = {}
    for p in sorted((root / "console").rglob("*.py")):
        parts = p.relative_to(root).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        mods[".".join(parts)] = p
    return mods


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST):
    """Every Import/ImportFrom node, at any depth, outside ``if TYPE_CHECKING:`` blocks."""
    todo = [tree]
    while todo:
        node = todo.pop()
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            todo.extend(node.orelse)
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        todo.extend(ast.iter_child_nodes(node))


def import_graph(root: Path = ROOT) -> dict[str, set[str]]:
    """module -> the console modules it imports (relative imports resolved)."""
    mods = module_files(root)
    graph: dict[str, set[str]] = {}
    for name, path in mods.items():
        pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
        edges: set[str] = set()
        for node in _imports(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                base = node.module or ""
                if node.level:
                    up = pkg.split(".")[: len(pkg.split(".")) - node.level + 1]
                    base = ".".join(up + ([base] if base else []))
                subs = [f"{base}.{a.name}" for a in node.names if f"{base}.{a.name}" in mods]
                targets = subs if subs and len(subs) == len(node.names) else [base, *subs]
            edges |= {t for t in targets if t in mods and t != name}
        graph[name] = edges
    return graph


def layer_of(module: str) -> str | None:
    best = None
    for prefix in LAYER_OF:
        exact = prefix == "console"
        match = module == prefix or (not exact and module.startswith(prefix + "."))
        if match and (best is None or len(prefix) > len(best)):
            best = prefix
    return LAYER_OF[best] if best else None


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """One import cycle as a list of modules (first repeated at the end), or None."""
    state: dict[str, int] = {}  # 1: on the current path, 2: done
    path: list[str] = []

    def visit(m: str) -> list[str] | None:
        state[m] = 1
        path.append(m)
        for n in sorted(graph.get(m, ())):
            if state.get(n) == 1:
                return path[path.index(n) :] + [n]
            if n not in state and (found := visit(n)):
                return found
        path.pop()
        state[m] = 2
        return None

    for m in sorted(graph):
        if m not in state and (found := visit(m)):
            return found
    return None


def test_every_console_module_has_a_layer():
    unknown = sorted(m for m in module_files() if layer_of(m) is None)
    assert not unknown, (
        f"{unknown}: not in a layer; add each to LAYER_OF in tests/console/test_layers.py "
        f"(layers, lowest first: {' -> '.join(LAYERS)})"
    )


def test_every_console_module_sits_in_a_layer_folder():
    """No module flat at console/'s root: a new module goes into the folder of its layer."""
    flat = sorted(p.name for p in (ROOT / "console").glob("*.py") if p.name != "__init__.py")
    assert not flat, f"{flat}: move each into the console/ folder of its layer (see LAYER_OF)"


def test_no_module_imports_a_higher_layer():
    rank = {layer: i for i, layer in enumerate(LAYERS)}
    up = [
        f"{m} ({layer_of(m)}) imports {t} ({layer_of(t)})"
        for m, targets in sorted(import_graph().items())
        for t in sorted(targets)
        if layer_of(m) and layer_of(t) and rank[layer_of(t)] > rank[layer_of(m)]
    ]
    assert not up, "imports of a higher layer:\n" + "\n".join(up)


def test_no_import_cycle_in_console():
    cycle = find_cycle(import_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle)


def test_the_checks_see_function_local_imports_and_skip_type_checking(tmp_path):
    """The graph the tests above judge: a cycle hidden in a function is found; a
    TYPE_CHECKING import is not an edge; a relative import is resolved."""
    pkg = tmp_path / "console"
    (pkg / "tui").mkdir(parents=True)
    (pkg / "config").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "tui" / "__init__.py").write_text("")
    (pkg / "config" / "__init__.py").write_text("")
    (pkg / "config" / "profile.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from console.tui import app\n"
        "def f():\n    from console import safety\n"
    )
    (pkg / "safety.py").write_text("from .config import profile\n")
    (pkg / "tui" / "app.py").write_text("from ..safety import check\n")
    graph = import_graph(tmp_path)
    assert graph["console.config.profile"] == {"console.safety"}
    assert graph["console.safety"] == {"console.config.profile"}
    assert graph["console.tui.app"] == {"console.safety"}
    assert find_cycle(graph) == [
        "console.config.profile",
        "console.safety",
        "console.config.profile",
    ]
    assert layer_of("console.tui.app") == "tui" and layer_of("console.new_thing") is None
