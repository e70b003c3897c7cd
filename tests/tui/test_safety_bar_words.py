"""The safety bar at 80 columns is shortened by whole words and fields, never cut in a
word (issue 27, third new-user try): a long e-stop reason loses its last words."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.safety_bar import SafetyBar, describe

from .conftest import wait_for

REASON = "e-stop from another process: a demo's watchdog tripped in stage vision (p99 412 ms)"


def _whole_words(shown: str, full: str) -> bool:
    """Every word of ``shown`` (a ``…`` at its end aside) is a word of ``full``."""
    words = set(full.split())
    return all(w in words for w in shown.removesuffix("…").split())


def test_a_long_estop_reason_loses_whole_words_at_80(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            app.estop(REASON)
            bar = app.query_one("#safety", SafetyBar)
            await wait_for(pilot, lambda: "ctrl+r" in str(bar.render()), 30, "e-stop shown")
            shown = str(bar.render())
            assert len(shown) <= 80 and "relays closed: none" in shown
            assert _whole_words(shown, f"E-STOP: ctrl+r resets | relays closed: none | {REASON}")

    asyncio.run(scenario())


def test_the_bar_never_cuts_a_word_at_any_width():
    status = {
        "gate": {"estopped": True, "estop_reason": REASON, "relays_closed": [5], "level_v": []},
        "busy": False,
    }
    full_text = describe(status, None)[0]
    full_text += " E-STOP: ctrl+r resets | relays closed: 5"
    for width in range(30, 100):
        text, _ = describe(status, width)
        assert len(text) <= width and _whole_words(text, full_text), (width, text)


def test_other_tables_e_stopped_never_hide_the_live_level_at_80():
    """A shell's `haptable estop` latched other tables too; this one, reset, plays: at
    80 columns the bar keeps its live level and says the others are e-stopped."""
    status = {
        "gate": {
            "estopped": False,
            "estop_reason": "",
            "relays_closed": [1, 2, 3, 4],
            "level_v": [12.3, 0.0],
        },
        "busy": True,
        "latched_elsewhere": ["haptable-lab", "sim-4ch"],
    }
    text, kind = describe(status, 80)
    assert kind == "live" and len(text) <= 80
    assert "piezo +12 V" in text and "e-stopped" in text, text


def test_other_tables_latched_never_take_this_tables_words():
    """A shell's bare `haptable estop` latched two unused tables: at 80 columns the idle
    bar still names what its closed relays switch (it showed `closed: 1,5` for the other
    tables' names), and an e-stopped bar never ends in a cut `+2…`."""
    from console.tui.safety_bar import describe

    names = {1: "PA", 5: "screen"}
    gate = {"estopped": False, "relays_closed": [1, 5], "level_v": [0.0, 0.0], "estop_reason": ""}
    idle = {"gate": gate, "busy": False, "latched_elsewhere": ["haptable-lab", "sim-4ch"]}
    text, _ = describe(idle, 80, names)
    assert "1,5 (PA screen)" in text and "haptable-lab" in text and len(text) <= 80, text
    stopped = {**idle, "gate": {**gate, "estopped": True, "estop_reason": "operator e-stop"}}
    text, _ = describe(stopped, 80, names)
    assert "operator e-stop" in text and not text.endswith("…") and len(text) <= 80, text
