"""A plugin sees the console through the plugin API only (DESIGN.md: llm's plugins see
``llm``, pytest's see ``pytest``): ``console.plugin_api`` (core, light),
``console.plugin_api.runtime`` and ``console.plugin_api.tui``. Read from the source (AST),
so an import inside a function, under ``if TYPE_CHECKING:`` or a module name given to
``importlib.import_module`` all count. ``api_violations(root)`` checks any plugin package,
built-in (``plugins/``) or third-party (its own folder)."""

from __future__ import annotations

import ast
import importlib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

#: the only console modules a plugin may import
PLUGIN_API = ("console.plugin_api", "console.plugin_api.runtime", "console.plugin_api.tui")


def _is_console(name: str) -> bool:
    return name == "console" or name.startswith("console.")


def _imported(node: ast.AST) -> list[str]:
    """The absolute modules one node imports (relative imports stay inside the plugin:
    none of them is the console)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if isinstance(node, ast.ImportFrom):
        if node.level or not node.module:
            return []
        if node.module == "console":  # ``from console import plugin_api``: the submodules
            return [f"console.{a.name}" for a in node.names]
        return [node.module]
    if (
        isinstance(node, ast.Call)
        and getattr(node.func, "attr", getattr(node.func, "id", ""))
        in ("import_module", "__import__")
        and node.args
        and isinstance(node.args[0], ast.Constant)
        and isinstance(node.args[0].value, str)
    ):
        return [node.args[0].value]
    return []


def api_violations(root: Path) -> list[str]:
    """``file:line: module`` for every import of a console module other than the plugin
    API in the ``.py`` files under ``root`` (a plugin package's folder)."""
    root = Path(root)
    bad = []
    for path in sorted(root.rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in ast.walk(tree):
            for mod in _imported(node):
                if _is_console(mod) and mod not in PLUGIN_API:
                    bad.append(f"{path.relative_to(root.parent)}:{node.lineno}: {mod}")
    return bad


def test_every_plugin_imports_the_console_through_the_plugin_api_only():
    bad = api_violations(REPO / "plugins")
    assert not bad, (
        "plugins import the console through console.plugin_api (core), "
        "console.plugin_api.runtime or console.plugin_api.tui only; add a name there "
        "if a plugin needs it:\n" + "\n".join(bad)
    )


def test_the_readmes_plugin_example_keeps_to_the_plugin_api(tmp_path):
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    block = readme.split("<!-- plugin-example -->", 1)[1].split("<!-- /plugin-example -->")[0]
    code = block.split("```python", 1)[1].rsplit("```", 1)[0]
    (tmp_path / "haptable_tick").mkdir()
    (tmp_path / "haptable_tick" / "__init__.py").write_text(code)
    assert "console.plugin_api" in code
    assert not api_violations(tmp_path / "haptable_tick")


@pytest.mark.parametrize("module", PLUGIN_API)
def test_every_name_the_plugin_api_offers_resolves(module):
    api = importlib.import_module(module)
    assert api.__doc__ and "plugin API" in api.__doc__
    assert len(api.__all__) == len(set(api.__all__)), "a name listed twice"
    missing = [name for name in api.__all__ if getattr(api, name, None) is None]
    assert not missing, f"{module}.__all__ names what it does not offer: {missing}"


def test_the_core_api_stays_light():
    """Importing ``console.plugin_api`` loads no Textual and no runtime; a runtime name
    loads its own module only (a plugin's settings may name one at registration)."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "import console.plugin_api\n"
        "from console.plugin_api.runtime import MAX_SOCKET_PATH\n"
        "print(' '.join(sorted(sys.modules)))\n"
    )
    got = subprocess.run(
        [sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=60
    )
    mods = set(got.stdout.split())
    assert "console.plugin_api" in mods, got.stderr
    heavy = sorted(
        m
        for m in mods
        if m.split(".")[0] in ("textual", "scipy", "plugins")
        or m.startswith(("console.tui.", "console.session", "console.runtime.stages"))
    )
    assert not heavy, heavy


@pytest.mark.parametrize(
    ("source", "expect"),
    [
        ("from console.core.errors import UserError", ["console.core.errors"]),
        ("def f():\n    from console.runtime.loop import FrameLoop", ["console.runtime.loop"]),
        ("import console.core.types", ["console.core.types"]),
        ("from console import paths", ["console.paths"]),
        (
            "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from console.tui.text import escape",
            ["console.tui.text"],
        ),
        ("import importlib\nimportlib.import_module('console.safety')", ["console.safety"]),
        ("from console.plugin_api import UserError", []),
        ("from console.plugin_api.runtime import FrameLoop", []),
        ("from console.plugin_api.tui import escape", []),
        ("from console import plugin_api", []),
        ("from .console import x\nimport consoles", []),
    ],
)
def test_the_check_catches_each_form_in_a_third_party_package(tmp_path, source, expect):
    pkg = tmp_path / "haptable_extra"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "mod.py").write_text(source + "\n")
    found = api_violations(pkg)
    assert [v.rsplit(": ", 1)[1] for v in found] == expect
    assert all(v.startswith("haptable_extra/mod.py:") for v in found)
