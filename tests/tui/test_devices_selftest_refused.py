"""Devices (F1): a self-test refused by the e-stop says so, leaves the self-test row as it
was (a refusal says nothing of the table's health), and the operator's reset replaces the
refusal on the status line, as it does for t (found by a new operator at 80 x 24: the
line stayed through resets and the row read "error")."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def _result(app) -> str:
    return app.pane("devices").result


async def _devices_ready(app, pilot):
    """The Devices pane once the outputs are open and the doctor's rows shown."""
    pane = app.pane("devices")
    await wait_for(pilot, lambda: app.session.outputs is not None, 20, "outputs")
    await wait_for(pilot, lambda: bool(pane.doctor_rows), 20, "doctor rows")
    return pane


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_s_during_an_estop_is_refused_and_the_reset_clears_it(plugins, size):
    """Refused in the console's words as on every screen, its key first (a new
    operator's try: it named `haptable reset` at a terminal first)."""

    # the paced table the console shares with the self-test (a fast twin is each
    # process's own: the self-test would open a table of its own)
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="devices")
        async with app.run_test(size=size) as pilot:
            pane = await _devices_ready(app, pilot)
            before = pane.doctor_rows[-1]
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 10, "e-stop")
            await pilot.press("s")
            await wait_for(pilot, lambda: "self-test refused" in _result(app), 30, "refused")
            line = _result(app)
            assert line.startswith("self-test refused: e-stop active ("), line
            assert line.endswith(", ctrl+r resets") and "haptable reset" not in line, line
            row = pane.doctor_rows[-1]  # a refusal ran nothing: the row as it was
            assert row.kind == "selftest" and row.state == before.state, (before, row)
            assert pane.selftest_done is None
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: _result(app).startswith("e-stop reset"), 10, "reset")

    asyncio.run(scenario())


def test_an_estop_during_the_self_test_says_stopped_and_the_reset_replaces_it(plugins):
    """A new operator's try: ctrl+e while the self-test ran left `self-test refused:
    self-test PC: stopped: operator e-stop (console)` after ctrl+r and on other screens:
    a test under way is stopped, not refused, and the reset replaces the line."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await _devices_ready(app, pilot)
            await pilot.press("s")
            await wait_for(pilot, lambda: "s again" in _result(app), 10, "asked")
            await pilot.press("s")
            await wait_for(pilot, lambda: "self-test:" in _result(app), 20, "running")
            await pilot.pause(1.0)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: "self-test stopped" in _result(app), 60, "stopped")
            line = _result(app)
            assert "refused" not in line, line  # stopped under way
            assert "ctrl+r resets" in line, line
            await pilot.press("f2", "f1")  # another screen and back: still true
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: _result(app).startswith("e-stop reset"), 10, "reset")

    asyncio.run(scenario())
