"""Every worker the console starts goes through ``console.tui.workers`` (its ``work`` and
``run_worker``): an unexpected exception in it is said on its screen, the outputs stop
and the console goes on, never Textual's default (the app exits). Read from the source
(AST): Textual's ``work`` imported, or a widget's ``run_worker`` called, anywhere else in
console/ or plugins/ fails."""

from __future__ import annotations

import ast
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
RULE = "console/tui/workers.py"


def bypasses(path: Path) -> list[str]:
    """The lines of ``path`` that start a worker around the rule."""
    tree = ast.parse(path.read_text(), str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("textual"):
            names = {a.name for a in node.names}
            if node.module == "textual" and "work" in names:
                found.append(f"{node.lineno}: from textual import work")
            if node.module == "textual.worker" and names & {"work", "Worker"}:
                found.append(f"{node.lineno}: from textual.worker import ...")
        elif isinstance(node, ast.Attribute) and node.attr in ("run_worker", "work"):
            base = node.value
            if node.attr == "run_worker" or (isinstance(base, ast.Name) and base.id == "textual"):
                found.append(f"{node.lineno}: .{node.attr}")
    return found


def test_every_worker_start_goes_through_the_rule():
    bad = []
    for top in ("console", "plugins"):
        for path in sorted((REPO / top).rglob("*.py")):
            rel = path.relative_to(REPO).as_posix()
            if rel != RULE:
                bad += [f"{rel}:{line}" for line in bypasses(path)]
    assert not bad, "start workers with console.tui.workers (work, run_worker):\n" + "\n".join(bad)


def test_the_check_sees_a_bypass(tmp_path):
    p = tmp_path / "m.py"
    p.write_text("from textual import work\nself.run_worker(f, thread=True)\n")
    assert len(bypasses(p)) == 2
