"""Plugin boundaries: the demos, vibrotactile and plate-twin plugins reach other plugins
only through registrations (DESIGN.md: never another plugin's internals)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2] / "plugins"

#: Imports of another plugin still needed, with why (reported to the lead):
#: the twin camera has no public looping demo script (only ``SequenceScript``), and
#: TUIO has no registration kind (an output sink of the frame loop).
ALLOWED = {
    ("demos", "plugins.twin.camera"),
    ("demos", "plugins.tuio"),
}


def plugin_of(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "plugins" or len(parts) < 2:
        return None
    if parts[1] == "twin" and len(parts) > 2 and parts[2] in ("plate", "camera"):
        return f"twin.{parts[2]}"
    return parts[1]


def imports(path: Path) -> set[str]:
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            out.add(node.module)
        elif isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
    return out


def test_no_plugin_internals_across_these_plugins():
    bad = []
    for owner, folder in (
        ("demos", ROOT / "demos"),
        ("vibrotactile", ROOT / "vibrotactile"),
        ("twin.plate", ROOT / "twin" / "plate"),
    ):
        for f in sorted(folder.rglob("*.py")):
            for mod in imports(f):
                other = plugin_of(mod)
                if other is None or other == owner or (owner, mod) in ALLOWED:
                    continue
                bad.append(f"{f.relative_to(ROOT.parent)} imports {mod}")
    assert not bad, "; ".join(bad)
