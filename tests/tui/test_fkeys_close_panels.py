"""An F-key over the help (``?``) or the log (``ctrl+l``) closes it and shows the screen
chosen (issue 27, third new-user try): the panel never stays on top of the new screen."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp, HelpScreen
from console.tui.logs import LogScreen

from .conftest import wait_for


@pytest.mark.parametrize(("key", "panel"), [("question_mark", HelpScreen), ("ctrl+l", LogScreen)])
def test_an_f_key_closes_the_panel_and_shows_its_screen(plugins, key, panel):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("devices") is not None, 30, "devices")
            await pilot.press(key)
            await wait_for(pilot, lambda: isinstance(app.screen, panel), 30, "panel open")
            f_key = app.tabs["relays"][1]
            await pilot.press(f_key)
            await wait_for(pilot, lambda: app.screen is app.base, 30, "panel closed")
            await wait_for(pilot, lambda: app.active_tab == "relays", 30, "relays shown")
            pane = app.pane("relays")
            await wait_for(pilot, lambda: app.shows(pane), 30, "relays in view")

    asyncio.run(scenario())
