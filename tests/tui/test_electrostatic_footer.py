"""The Electrostatic screen at 80x24 (issue 27): the footer shows every key the screen
needs, ``p`` (play the setting, its main action) first."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines


def test_the_footer_shows_every_electrostatic_key_at_80_columns(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="electrostatic")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("electrostatic")
            await wait_for(pilot, lambda: app.focused is pane.focus_target, 30, "the list")
            await pilot.pause(0.3)  # the footer laid out at this width
            footer = screen_lines(app)[-1]
            for key in ("p play", "t sine/square", "+ - Vpp", "[ ] Hz", "^e E-STOP"):
                assert key in footer, (key, footer)

    asyncio.run(scenario())
