"""A key's answer holds its screen's status line against the progress of work under
way (issue 27: Enter during a measurement was refused and the measurement's next
progress replaced the refusal 7 ms later, so it was never seen)."""

from __future__ import annotations

import asyncio
import time

import pytest

from console.cli.main import Context
from console.session.vibration import Cancelled
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_screens import _load_map, _ready


def _status(app) -> str:
    return str(app.query_one("#vib-status").render())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_refusal_during_a_measurement_stays_on_its_line(plugins, map_file, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            pane = await _load_map(app, pilot, map_file)
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="grid")

            def busy(progress, cancelled):  # reports every 10 ms until x
                i = 0
                while not cancelled():
                    i += 1
                    progress(min(i / 2000, 0.99), f"point {i % 90 + 1}")
                    time.sleep(0.01)
                raise Cancelled

            pane.service.measure = busy
            pane.action_measure("measure")
            await wait_for(pilot, lambda: "measuring:" in _status(app), 10, "progress")
            pane.move_cursor(3)
            await pilot.press("enter")
            await wait_for(pilot, lambda: "refused" in _status(app), 10, "refused")
            t0 = time.monotonic()
            while time.monotonic() - t0 < 1.5:  # still there while it can be read
                await pilot.pause(0.1)
                assert "the map is being measured (x stops the measurement)" in _status(app)
            await pilot.press("x")
            await wait_for(pilot, lambda: pane._measuring is None, 20, "measurement stopped")
            assert "cancelled" in _status(app)

    asyncio.run(scenario())
