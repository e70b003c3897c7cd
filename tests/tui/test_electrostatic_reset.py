"""The Electrostatic screen's status line drops what the e-stop did at the reset: a play
the e-stop stopped is no longer said once the operator reset it (issue 27)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on


def _status(app) -> str:
    return words_on(app, "#es-status")


def test_a_play_stopped_by_the_estop_is_not_said_after_the_reset(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="electrostatic")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: app.query("#es-status"), 30, "screen")
            await pilot.press("p")
            await wait_for(pilot, lambda: _status(app).startswith("playing"), 30, "playing")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: "stopped by the e-stop" in _status(app), 30, "stop")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 30, "reset")
            await wait_for(pilot, lambda: "e-stop reset" in _status(app), 30, "reset said")
            assert "stopped" not in _status(app), _status(app)

    asyncio.run(scenario())
