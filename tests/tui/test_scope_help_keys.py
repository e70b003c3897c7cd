"""Scope (F9): its help lists every key of a recording the README names (o, [ ], e, Esc),
each at the start of a line, and both ways to make a recording the screen's own error
names (a new operator found `e` missing and the two texts disagreeing)."""

from __future__ import annotations

from console.tui.panes.scope import ScopePane
from console.tui.scope_recording import SCOPE_REPLAY_BINDINGS


def test_the_help_lists_each_recording_key_and_both_ways_to_record():
    lines = ScopePane.HELP_TEXT.splitlines()
    starts = [line.split("  ")[0].strip() for line in lines if not line.startswith(" ")]
    for b in SCOPE_REPLAY_BINDINGS:
        if b.action == "plan_step(-1)":  # shown with its pair, "[ / ]"
            continue
        shown = {"escape": "Esc", "right_square_bracket": "[ / ]"}.get(b.key, b.key)
        assert shown in starts, (b.key, starts)
    said = " ".join(ScopePane.HELP_TEXT.split())
    assert "haptable demo flow --record FILE" in said
    assert "[recording] enabled = true" in said
