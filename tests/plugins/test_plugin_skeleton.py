"""Every plugin has the same skeleton (issue 26): its ``__init__.py`` holds the pluggy
hook implementations and the imports they need, nothing else. A profile section lives
in ``settings.py``, commands in ``cli.py``, a console panel in ``panel.py``, benchmarks
in ``bench.py``, any other helper in a module named for what it holds."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: sub-plugins with a package of their own (``plugins/<name>/<sub>/__init__.py``)
SUB_PLUGINS = ("twin/plate", "twin/camera")
#: module-level names an ``__init__`` may bind besides its imports and hooks
ALLOWED_NAMES = frozenset({"__all__"})


def plugin_inits(root: Path = ROOT) -> list[Path]:
    """``plugins/*/__init__.py`` and the sub-plugins' ``__init__.py``."""
    found = sorted((root / "plugins").glob("*/__init__.py"))
    found += [root / "plugins" / s / "__init__.py" for s in SUB_PLUGINS]
    return [p for p in found if p.is_file()]


def _is_hookimpl(dec: ast.expr) -> bool:
    node = dec.func if isinstance(dec, ast.Call) else dec
    return (isinstance(node, ast.Name) and node.id == "hookimpl") or (
        isinstance(node, ast.Attribute) and node.attr == "hookimpl"
    )


def strays(path: Path, root: Path = ROOT) -> list[str]:
    """What an ``__init__`` holds that is no hook implementation: ``file:line kind
    name`` of each top-level def or class not decorated with ``hookimpl``, and of each
    module-level name it binds by assignment."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    rel = path.relative_to(root).as_posix()
    out = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            if not any(_is_hookimpl(d) for d in node.decorator_list):
                kind = "class" if isinstance(node, ast.ClassDef) else "function"
                out.append(f"{rel}:{node.lineno} {kind} {node.name}")
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            names = node.targets if isinstance(node, ast.Assign) else [node.target]
            for t in names:
                for n in ast.walk(t):
                    if isinstance(n, ast.Name) and n.id not in ALLOWED_NAMES:
                        out.append(f"{rel}:{node.lineno} name {n.id}")
    return out


def _rel(p: Path, root: Path = ROOT) -> str:
    return p.relative_to(root).as_posix()


def test_a_plugins_init_holds_hook_implementations_only():
    bad = [s for p in plugin_inits() for s in strays(p)]
    assert not bad, (
        "a plugin's __init__.py holds its @hookimpl functions only; move each of these to "
        "a module named for what it holds (settings.py, cli.py, bench.py, ...) or nest a "
        "factory inside the hook that registers it:\n" + "\n".join(bad)
    )


def test_the_check_names_file_and_stray(tmp_path):
    f = tmp_path / "plugins" / "demo" / "__init__.py"
    f.parent.mkdir(parents=True)
    f.write_text(
        "from console.plugin_api import hookimpl\n"
        "import pluggy\n"
        "LIMIT = 3\n"
        "@hookimpl\ndef haptable_register_commands(register):\n"
        "    def run(args, ctx):\n        return 0\n"
        "@pluggy.HookimplMarker('haptable')\ndef other(): ...\n"
        "@hookimpl(tryfirst=True)\ndef haptable_profile_sections(register): ...\n"
        "def helper(): ...\n"
        "class Factory: ...\n"
    )
    assert strays(f, tmp_path) == [
        "plugins/demo/__init__.py:3 name LIMIT",
        "plugins/demo/__init__.py:9 function other",
        "plugins/demo/__init__.py:12 function helper",
        "plugins/demo/__init__.py:13 class Factory",
    ]
