"""An F-key closes the help and the log, however fast it comes (issue 27: ``ctrl+l F3``
in one write, ``tmux send-keys C-l F3``, left the log on top; ``?`` then F5 worked)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.help_screen import HelpScreen
from console.tui.logs import LogScreen

from .conftest import wait_for
from .test_estop_toast_latest import _one_write
from .test_screens import _ready


@pytest.mark.parametrize("first", ["ctrl+l", "question_mark"])
@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_an_fkey_right_behind_the_log_key_shows_its_screen(plugins, size, first):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            _one_write(app, first, "f3")
            await wait_for(pilot, lambda: app.active_tab == "vibration", 20, "Vibration")
            await pilot.pause(1.0)
            assert app.screen is app.base, app.screen
            assert not isinstance(app.screen, (LogScreen, HelpScreen))

    asyncio.run(scenario())
