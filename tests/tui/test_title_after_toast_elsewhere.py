"""Issue 27: after an e-stop and its reset (ctrl+e, ctrl+r) the title row showed only
``⭘`` for minutes, on every screen (F1, F2, F3, F6): the reset's toast, wide at 80
columns, left the title no room, and it ended while the log (ctrl+l) was in front. Only
that screen's title was laid out again when the toast went; the console's own header
kept the cut it had beside the toast until the next one. Every screen's title is laid
out again when the toast changes."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_title_comes_back_after_a_toast_that_ended_behind_the_log(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size, notifications=True) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            title = f"{app.title} — {app.sub_title}"  # as the header shows them
            await wait_for(pilot, lambda: title in screen_lines(app)[0], 10, "the title")
            app.notify("e-stop reset: outputs stay silent until something plays " * 2, timeout=4)
            await wait_for(pilot, lambda: title not in screen_lines(app)[0], 10, "cut by it")
            await pilot.press("ctrl+l")  # the log in front while the toast ends
            await wait_for(pilot, lambda: app.screen is not app.base, 10, "the log")
            await wait_for(pilot, lambda: app.toast_x is None, 10, "the toast gone")
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.screen is app.base, 10, "back")
            await pilot.pause(0.3)
            await wait_for(pilot, lambda: title in screen_lines(app)[0], 5, screen_lines(app)[0])

    asyncio.run(scenario())
