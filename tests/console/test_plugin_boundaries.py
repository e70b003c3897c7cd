"""Plugin boundaries (DESIGN.md): a plugin never imports another plugin's internals; they
meet through registrations (console/core/hookspecs.py) and the values of console/core/types.py.
Read from the source (AST), so an import inside a function, a relative import and
``importlib.import_module("plugins...")`` all count. Sub-plugins (``twin.plate``,
``twin.camera``) are plugins of their own. (console/ importing no plugin at all is
tests/tui/test_no_plugin_imports.py.)"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from console.config.plugins import BUILTIN_PLUGINS

REPO = Path(__file__).resolve().parents[2]


def plugin_of(module: str) -> str | None:
    """The built-in plugin a module belongs to: the longest matching plugin package
    (``plugins.twin.camera.render`` -> ``twin.camera``, ``plugins.twin.outputs`` ->
    ``twin``); ``None`` outside plugins/."""
    mine = [n for n, p in BUILTIN_PLUGINS.items() if module == p or module.startswith(p + ".")]
    best = max(mine, key=lambda n: len(BUILTIN_PLUGINS[n]), default=None)
    if best is None and (module == "plugins" or module.startswith("plugins.")):
        return module  # a plugins/ module that is no registered plugin: always foreign
    return best


def module_name(path: Path, repo: Path = REPO) -> str:
    parts = list(path.relative_to(repo).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def imported_modules(path: Path, repo: Path = REPO) -> list[tuple[int, str]]:
    """(line, absolute module) of every import in a file, relative ones resolved."""
    package = module_name(path, repo)
    if path.name != "__init__.py":
        package = package.rpartition(".")[0]
    out = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.append((node.lineno, mod))
            # ``from plugins import tuio``, ``from plugins.twin import camera``: a plugin
            subs = [f"{mod}.{a.name}" for a in node.names if a.name != "*"]
            out += [(node.lineno, m) for m in subs if plugin_of(m) != plugin_of(mod)]
        elif (
            isinstance(node, ast.Call)
            and getattr(node.func, "attr", getattr(node.func, "id", "")) == "import_module"
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and isinstance(node.args[0].value, str)
        ):
            out.append((node.lineno, node.args[0].value))
    return out


def cross_plugin_imports(repo: Path = REPO) -> list[str]:
    bad = []
    for f in sorted((repo / "plugins").rglob("*.py")):
        owner = plugin_of(module_name(f, repo))
        for line, mod in imported_modules(f, repo):
            other = plugin_of(mod)
            if other is None or other == owner:
                continue
            if mod == "plugins":  # the namespace package itself (``from plugins import x``)
                continue
            bad.append(f"{f.relative_to(repo)}:{line} ({owner}) imports {mod} ({other})")
    return bad


def test_no_plugin_imports_another_plugins_internals():
    bad = cross_plugin_imports()
    assert not bad, "meet through a registration or a console type instead:\n" + "\n".join(bad)


def test_every_plugins_package_is_a_plugin_the_guard_knows():
    """A new folder under plugins/ must be listed (or be part of a listed plugin), or the
    guard above would treat its own imports as foreign."""
    for d in sorted((REPO / "plugins").iterdir()):
        if (d / "__init__.py").is_file():
            assert plugin_of(f"plugins.{d.name}") is not None


@pytest.mark.parametrize(
    ("source", "where", "expect"),
    [
        ("from plugins.tuio import make_sender", "plugins/demos/run.py", True),
        ("import plugins.twin.camera", "plugins/gestures/synth.py", True),
        ("from ..camera import Rig", "plugins/twin/plate/x.py", True),  # sibling sub-plugin
        ("from plugins import tuio", "plugins/demos/run.py", True),
        ("from plugins.twin import camera", "plugins/twin/outputs.py", True),
        (
            "def f():\n    import importlib\n    importlib.import_module('plugins.tuio')",
            "plugins/demos/run.py",
            True,
        ),
        ("from plugins.twin.outputs import TwinAudioOutput", "plugins/twin/__init__.py", False),
        ("from .render import Rig", "plugins/twin/camera/camera.py", False),
        ("from plugins.demos.run import start_demo", "plugins/demos/cli.py", False),
        ("from console.core.types import Frame", "plugins/demos/run.py", False),
    ],
)
def test_the_guard_catches_what_it_should(tmp_path, source, where, expect):
    f = tmp_path / where
    f.parent.mkdir(parents=True)
    f.write_text(source + "\n")
    assert bool(cross_plugin_imports(tmp_path)) is expect


def effects_by_name(root: Path) -> list[str]:
    """Places in plugins/ that fetch another registration of kind ``effect`` by its name
    (``plugins.get("effect", "x")``, ``plugins.of("effect").get("x")``)."""
    found = []
    for path in sorted((root / "plugins").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
                continue
            args = [a.value for a in node.args if isinstance(a, ast.Constant)]
            inner = node.func.value
            by_get = node.func.attr == "get" and args[:1] == ["effect"] and len(args) == 2
            by_of = (
                node.func.attr == "get"
                and isinstance(inner, ast.Call)
                and isinstance(inner.func, ast.Attribute)
                and inner.func.attr == "of"
                and [a.value for a in inner.args if isinstance(a, ast.Constant)] == ["effect"]
            )
            if by_get or by_of:
                found.append(f"{path.relative_to(root)}:{node.lineno}")
    return found


def test_plugins_ask_for_effects_by_capability_never_by_name():
    assert effects_by_name(REPO) == [], (
        "ask plugins.provider('effect', <a console.core.contracts Protocol>, profile) instead"
    )


def test_the_effect_name_guard_catches_both_spellings(tmp_path):
    f = tmp_path / "plugins" / "x" / "a.py"
    f.parent.mkdir(parents=True)
    f.write_text('pm.get("effect", "flow")\npm.of("effect").get("knob")\npm.get("x")\n')
    assert effects_by_name(tmp_path) == ["plugins/x/a.py:1", "plugins/x/a.py:2"]
