"""The Relays screen and the safety bar say what is true (issue 27): a reset clears the
refusals the e-stop caused, the switch log gives times (not sample counts), and the
relays are named as the profile names them (PA..PD, screen)."""

from __future__ import annotations

import asyncio
import re

from textual.widgets import DataTable

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.safety_bar import SafetyBar, describe

from .conftest import wait_for


def _interlock(app, ch: int) -> str:
    return str(app.query_one(f"#interlock-{ch}").render())


def _bar(app) -> str:
    return str(app.query_one(SafetyBar).render())


def test_a_reset_clears_the_refusal_the_estop_caused(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            pane = app.pane("relays")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stopped")
            await pilot.press("1")
            await wait_for(pilot, lambda: 1 in pane.refused, 10, "refused")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            await wait_for(pilot, lambda: "ready" in _interlock(app, 1), 10, "ready again")
            assert "refused" not in _interlock(app, 1)
            assert _interlock(app, 1).startswith("open - ready")  # its state now

    asyncio.run(scenario())


def test_the_switch_log_gives_times_and_names_and_the_bar_names_the_relays(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            await pilot.press("1")
            log = app.query_one("#relaylog", DataTable)
            await wait_for(pilot, lambda: log.row_count == 1, 10, "logged")
            row = [str(c) for c in log.get_row_at(0)]
            assert re.fullmatch(r"\d+\.\d\d\d s", row[0]), row
            clock = app.session.outputs.relay_log()[-1].clock
            assert row[0] == f"{clock / 48000:.3f} s", row
            assert "PA" in row[1], row
            # each output's level named, in the sound card's channel order
            assert row[3] == "piezo +0.0 V / screen +0.0 V", row
            await wait_for(pilot, lambda: "PA" in _bar(app), 10, "bar names relay 1")

    asyncio.run(scenario())


def test_the_bar_names_the_closed_relays_from_the_profile(plugins):
    from console.config.profile import load_profile
    from console.tui.safety_bar import relay_names

    names = relay_names(load_profile("sim", plugins))
    assert names == {1: "PA", 2: "PB", 3: "PC", 4: "PD", 5: "screen"}
    gate = {
        "estopped": False,
        "estop_reason": "",
        "level_v": [0.0, 0.0],
        "channels": ["piezo", "screen"],
        "relays_closed": [1, 2, 5, 6, 8],
    }
    text, _ = describe({"gate": gate, "busy": False}, 200, names)
    assert "PA PB screen" in text, text
    for width in (80, 60):
        text, _ = describe({"gate": gate, "busy": False}, width, names)
        assert "ctrl+e" in text or "^e" in text
        assert len(text) <= width


def test_during_an_estop_only_the_pressed_relay_reads_refused():
    from console.tui.panes.relays import interlock

    status = {"gate": {"estopped": True}, "busy": False}
    assert "refused: e-stop active" in interlock(1, status, {}, {1: "e-stop active"})
    other = interlock(2, status, {}, {1: "e-stop active"})
    assert (
        "refused" not in other
        and other.startswith("open - ")
        and "e-stop active" in other
        and "ctrl+r" in other
    )
