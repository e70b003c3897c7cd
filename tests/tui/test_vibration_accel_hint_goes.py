"""A new operator's try (80 x 24): after ``m`` the one-line accelerometer hint stayed for
the rest of the session, the grid a row lower. It goes with the next key, or when the
measurement ends (measured, cancelled, failed), whichever comes first; the grid moves back
up. ``?`` still says whole how to add an accelerometer input."""

from __future__ import annotations

import asyncio
import threading
import time

from console.cli.main import Context
from console.session.vibration import Cancelled
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines
from .test_screens import _ready

HINT = "measuring with the vibrometer; ? says how to add an accelerometer input"


def _shown(app) -> bool:
    return any(HINT in ln for ln in screen_lines(app))


def _grid_y(app) -> int:
    return app.query_one("#grid").region.y


def test_the_hint_goes_with_the_next_key(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            service = app.session.vibration

            def measure(progress, cancelled):  # the twin's measurement, until x
                while not cancelled():
                    time.sleep(0.02)
                raise Cancelled()

            service.measure = measure
            await pilot.press("m")
            await wait_for(pilot, lambda: _shown(app), 30, "the hint after m")
            with_hint = _grid_y(app)
            grid = app.query_one("#grid")
            row = grid.cursor_coordinate.row
            await pilot.press("down")  # the next key: the grid's cursor moves, the hint goes
            await wait_for(pilot, lambda: not _shown(app), 10, "the hint gone")
            assert grid.cursor_coordinate.row == row + 1, "the key did what it does too"
            assert pane._measuring is not None, "the measurement still runs"
            assert _grid_y(app) == with_hint - 1  # the grid back up: the hint's row gone
            await pilot.press("x")
            await wait_for(pilot, lambda: pane._measuring is None, 30, "measurement ended")
            assert "measurement cancelled" in pane.status_text

    asyncio.run(scenario())


def test_the_hint_goes_when_the_measurement_ends(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            release = threading.Event()
            service = app.session.vibration

            def measure(progress, cancelled):  # a measured map, when the test says
                release.wait(30)
                return service.load(map_file)

            service.measure = measure
            await pilot.press("m")
            await wait_for(pilot, lambda: _shown(app), 30, "the hint after m")
            release.set()  # no key pressed: the measurement ends
            await wait_for(pilot, lambda: pane.session is not None, 30, "map measured")
            await wait_for(pilot, lambda: not _shown(app), 30, "the hint gone")
            # its row gone (removed with the screen's next refresh: a loaded machine drew
            # the hint's absence before the row left)
            await wait_for(pilot, lambda: not app.query("#vib-roving"), 30, "its row gone")
            assert "[audio_inputs.accel] channel = 1" in pane.HELP_TEXT

    asyncio.run(scenario())
