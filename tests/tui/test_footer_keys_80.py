"""Issue 27, fourth new-user try: footers at 80x24 name the keys as they work. Relays
shows its eight keys as one entry ("1-8 toggle"), Vibration its four hand keys as one
("w a s d hand"), and the Camera screen shows the calibration wizard's keys (n, x)
while it runs, and not once it is cancelled."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera import _first_frame
from .test_camera_layout import screen_lines


def _footer(app) -> str:
    return screen_lines(app)[-1]


def _open(plugins, initial: str) -> HapTableApp:
    return HapTableApp(Context("sim", plugins), fast=True, initial=initial)


async def _footer_shows(plugins, tab: str, want: str, not_want: str) -> None:
    app = _open(plugins, tab)
    async with app.run_test(size=(80, 24)) as pilot:
        await wait_for(pilot, lambda: want in _footer(app), 30, f"{want!r} in footer")
        assert not_want not in _footer(app), _footer(app)


def test_relays_and_vibration_footers_show_their_key_groups_whole(plugins):
    asyncio.run(_footer_shows(plugins, "relays", "1-8 toggle", "1 relay 1"))
    asyncio.run(_footer_shows(plugins, "vibration", "w a s d hand", "hand w/a/s/d"))


def test_the_camera_footer_shows_the_calibration_wizards_keys_while_it_runs(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("camera")
            await _first_frame(app, pilot)
            await wait_for(pilot, lambda: "k calibrate" in _footer(app), 30, "camera footer")
            assert "skip target" not in _footer(app), _footer(app)
            await pilot.press("k")
            await wait_for(pilot, lambda: pane.calibration is not None, 30, "wizard running")
            await wait_for(pilot, lambda: "n skip target" in _footer(app), 30, "n in footer")
            assert "x cancel" in _footer(app), _footer(app)
            await pilot.press("x")
            await wait_for(pilot, lambda: pane.calibration is None, 30, "cancelled")
            await wait_for(pilot, lambda: "skip target" not in _footer(app), 30, "n gone")
            assert "x cancel" not in _footer(app), _footer(app)

    asyncio.run(scenario())
