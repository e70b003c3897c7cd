"""The Relays screen's rows say each relay's state as the gate reports it, then why it
can or cannot switch; an e-stop that opened the operator's relay says so after the
reset until the operator toggles it, and nothing from before the reset stays (issue 27)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def _row(app, ch: int) -> str:
    return " ".join(str(app.query_one(f"#interlock-{ch}").render()).split())


def test_each_row_starts_with_the_relay_s_state(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: _row(app, 3).startswith("open"), 30, "open row")
            await pilot.press("3")
            await wait_for(pilot, lambda: _row(app, 3).startswith("closed"), 30, "closed")
            assert _row(app, 1).startswith("open"), _row(app, 1)

    asyncio.run(scenario())


def test_the_estop_opening_your_relay_is_said_until_you_toggle_it(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("3")
            await wait_for(pilot, lambda: _row(app, 3).startswith("closed"), 30, "closed")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 30, "e-stopped")
            await wait_for(pilot, lambda: _row(app, 3).startswith("open"), 30, "opened")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 30, "reset")
            want = "open - the e-stop opened it; press 3 to close again"
            await wait_for(pilot, lambda: _row(app, 3) == want, 30, "said after reset")
            assert "e-stop" not in _row(app, 1), _row(app, 1)  # it was open before
            await pilot.press("3")
            await wait_for(pilot, lambda: _row(app, 3).startswith("closed"), 30, "closed again")
            assert "e-stop" not in _row(app, 3), _row(app, 3)

    asyncio.run(scenario())


def test_a_toggle_refused_in_the_estop_leaves_no_stale_line_after_the_reset(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 30, "e-stopped")
            await pilot.press("1")
            await wait_for(pilot, lambda: "refused" in _row(app, 1), 30, "refused")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 30, "reset")
            await wait_for(pilot, lambda: "refused" not in _row(app, 1), 30, "cleared")
            assert _row(app, 1).startswith("open"), _row(app, 1)
            assert "press again" not in _row(app, 1), _row(app, 1)
            await pilot.press("1")  # the operator's toggle runs: the row says closed
            await wait_for(pilot, lambda: _row(app, 1).startswith("closed"), 30, "closed")
            assert "e-stop" not in _row(app, 1), _row(app, 1)

    asyncio.run(scenario())


def test_a_status_read_before_the_estop_arriving_after_it_does_not_hide_what_it_opened(
    plugins,
):
    """The console's status read just before the e-stop can reach the screen after the
    e-stop's event: it must not take back that the e-stop opened relay 3."""
    from console.session.events import Started, Stopped
    from console.tui.session_messages import SessionMessage

    def status(estopped: bool, closed: list[int], operator: list[int]) -> dict:
        gate = {"estopped": estopped, "relays_closed": closed}
        return {"gate": gate, "busy": False, "operator_relays": operator}

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            pane = app.pane("relays")
            pane.show_state(status(False, [3], [3]), None)
            pane.on_session_message(SessionMessage(Stopped("estop", reason="test")))
            pane.show_state(status(False, [3], [3]), None)  # read before, arrives after
            pane.on_session_message(SessionMessage(Started("estop")))
            pane.show_state(status(False, [], []), None)
            assert _row(app, 3) == "open - the e-stop opened it; press 3 to close again"

    asyncio.run(scenario())
