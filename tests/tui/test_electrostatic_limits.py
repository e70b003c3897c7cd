"""Issue 27, fourth new-user try: a key that cannot change the Electrostatic setting (+
at the screen's maximum) says which limit stops it on the status line, in place of an
older line about something else; the next key that moves the setting clears it."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_screens import _ready


def test_plus_at_the_maximum_says_which_limit_stops_it(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="electrostatic")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("electrostatic")
            pane.say("e-stop reset: p or enter plays")  # an older line, about the e-stop
            steps = int((pane.max_vpp - pane.vpp) / 10) + 1
            for _ in range(steps):
                await pilot.press("plus")
            line = lambda: words_on(app, "#es-status")  # noqa: E731
            top = f"{pane.max_vpp:g} Vpp"
            await wait_for(pilot, lambda: "maximum" in line(), 10, "the limit said")
            assert f"{top} is the screen's maximum ([limits] screen_max_vpp)" in line(), line()
            assert "e-stop reset" not in line(), line()
            await pilot.press("minus")
            await wait_for(pilot, lambda: "maximum" not in line(), 10, "the limit line cleared")

    asyncio.run(scenario())
