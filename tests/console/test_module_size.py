"""Small modules with names that say what they hold: no module of the console or its
plugins grows past ``MAX_LINES`` (split it by job, as DESIGN.md's habits ask)."""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
MAX_LINES = 700


def test_no_module_is_over_the_limit():
    over = {
        str(p.relative_to(ROOT)): n
        for top in ("console", "plugins")
        for p in sorted((ROOT / top).rglob("*.py"))
        if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES
    }
    assert not over, f"modules over {MAX_LINES} lines (split them by job): {over}"
