"""The console never imports a plugin: it meets them through registrations
(``console/core/hookspecs.py``) and ``console`` types. An AST scan of every module under
``console/`` for imports of ``plugins`` (static, or a module name given to
``importlib.import_module`` / ``__import__``) and for ``plugins.*`` module-name strings,
allowing only the built-in plugin list (the projector plugin registers its own command)."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import console
from console.config.plugins import BUILTIN_PLUGINS

ROOT = Path(console.__file__).resolve().parent

#: module-name strings the console may hold: (file relative to console/, string)
ALLOWED_STRINGS = {
    # the built-in plugins registered by name, exactly like entry-point plugins
    *(("config/plugins.py", m) for m in BUILTIN_PLUGINS.values()),
}
MODULE_NAME = re.compile(r"plugins\.([A-Za-z_]\w*(\.[A-Za-z_]\w*)*\.?)?")  # not bare "plugins"


def _is_plugins(name: str | None) -> bool:
    return bool(name) and (name == "plugins" or name.startswith("plugins."))


def violations(path: Path, rel: str) -> list[str]:
    out = []
    tree = ast.parse(path.read_text(), filename=str(path))
    for node in ast.walk(tree):
        where = f"{rel}:{getattr(node, 'lineno', '?')}"
        if isinstance(node, ast.Import):
            out += [f"{where}: import {a.name}" for a in node.names if _is_plugins(a.name)]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and _is_plugins(node.module):
            out.append(f"{where}: from {node.module} import ...")
        elif (
            isinstance(node, ast.Constant)
            and isinstance(node.value, str)
            and MODULE_NAME.fullmatch(node.value)
            and (rel, node.value) not in ALLOWED_STRINGS
        ):
            out.append(f"{where}: module name {node.value!r}")
    return sorted(out, key=lambda v: int(v.split(":")[1]))


def test_no_module_under_console_imports_a_plugin():
    found = []
    for path in sorted(ROOT.rglob("*.py")):
        found += violations(path, path.relative_to(ROOT).as_posix())
    assert not found, "console/ must not import plugins/*:\n" + "\n".join(found)


def test_the_scan_catches_each_form(tmp_path):
    bad = tmp_path / "bad.py"
    bad.write_text(
        "import plugins.twin\n"
        "from plugins.vibrotactile.tables import build_tables\n"
        "def f():\n"
        "    from plugins import gestures\n"
        "    import importlib\n"
        "    importlib.import_module('plugins.electrostatic.synth')\n"
        "    importlib.import_module(f'plugins.{f.__name__}')\n"
        "x = {'plugins': 'plugins and what they provide'}\n"  # a word, prose: fine
    )
    got = violations(bad, "tui/bad.py")
    assert [g.split(":")[1] for g in got] == ["1", "2", "4", "6", "7"], got
    # allowed strings are per file and value: config/plugins.py may name plugins.twin only
    again = violations(bad, "config/plugins.py")
    assert [g.split(":")[1] for g in again] == ["1", "2", "4", "6", "7"], again
