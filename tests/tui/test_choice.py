"""Every drop-down offers its choices only: no source builds a bare Textual ``Select``
(whose blank entry a new operator picked on Studies: protocol and folder named
``Select.NULL``), nor compares with ``Select.BLANK`` (not Textual 8's no-choice value);
``chosen`` reads a drop-down's value as text, "" for none."""

from __future__ import annotations

import ast
from pathlib import Path

from textual.widgets import Select

from console.plugin_api.tui import chosen

ROOT = Path(__file__).resolve().parents[2]


def _bare_selects() -> list[str]:
    """Where a source builds Textual's own ``Select(...)`` or reads ``Select.BLANK``."""
    found = []
    for top in ("console", "plugins"):
        for path in (ROOT / top).rglob("*.py"):
            if path.name == "choice.py":
                continue
            for node in ast.walk(ast.parse(path.read_text())):
                f = node.func if isinstance(node, ast.Call) else None
                called = f.id if isinstance(f, ast.Name) else getattr(f, "attr", "")
                blank = isinstance(node, ast.Attribute) and node.attr == "BLANK"
                if called == "Select" or blank:
                    found.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    return found


def test_every_drop_down_is_a_choice_without_a_blank_entry():
    assert _bare_selects() == []


def test_chosen_is_empty_for_no_choice():
    assert chosen(Select.NULL) == "" and chosen(None) == ""
    assert chosen("exp1") == "exp1"
