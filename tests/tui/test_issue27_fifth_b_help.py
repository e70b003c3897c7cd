"""Issue 27 (fifth, b): the Latency and Relays help say what the screens do: a sparkline
is a bar per reading, growing to the screen's width (not "as wide as the screen" from the
start); the Relays help names the on-screen switch log as the screen does."""

from __future__ import annotations

from console.tui.panes.latency import MEASURE_S, TICK_S, LatencyPane
from console.tui.panes.relays import RelaysPane


def _words(text: str) -> str:
    return " ".join(text.split())


def test_latency_help_says_how_wide_a_sparkline_is():
    said = _words(LatencyPane.HELP_TEXT)
    # a sparkline spans the row (a new operator's 21-42 columns at 120x40 were too
    # narrow), its readings stretched over it; the help says how many m's run gives
    assert "as wide as the screen" in said and "stretched over it" in said
    assert f"{MEASURE_S / TICK_S:.0f} readings" in said


def test_relays_help_names_the_switch_log():
    said = _words(RelaysPane.HELP_TEXT)
    assert "The switch log below lists every switch" in said
    assert "The log lists" not in said
