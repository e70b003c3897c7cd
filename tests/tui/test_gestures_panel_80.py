"""The Gestures panel (Camera ``g``) at 80 x 24 (issue 27): its footer shows E-STOP and
``f1-f10`` as every screen's does; an F-key closes the panel and shows that screen (while
work runs there it stays and says why, on its own line); the size and time ``s`` asks
about shows whole."""

from __future__ import annotations

import asyncio
import re
import threading

from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines, text_in

SIZE = (80, 24)


async def _panel(app, pilot, plugins):
    await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
    app.push_screen(plugins.of("panel")["gestures"].factory(app))
    await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel", 30, "panel")
    panel = app.screen
    await wait_for(pilot, lambda: bool(panel.query("#gp-files")), 30, "panel composed")
    return panel


def _footer_complete(app) -> bool:
    footer = screen_lines(app)[-1]
    return all(k in footer for k in ("^e E-STOP", "f1-f10 screens", "? help"))


def test_the_footer_shows_e_stop_and_f_keys_and_an_f_key_shows_its_screen(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=SIZE) as pilot:
            panel = await _panel(app, pilot, plugins)
            await wait_for(pilot, lambda: _footer_complete(app), 30, screen_lines(app)[-1])
            # work under way: the panel stays and says why on its own line
            release = threading.Event()
            panel.work.start("training", lambda progress, cancelled: release.wait(30))
            await pilot.press("f6")
            work = panel.work  # said under the work's progress
            await wait_for(pilot, lambda: "x cancels" in text_in(app, work), 30, "refused")
            assert app.screen is panel and app.active_tab == "devices"
            release.set()
            await wait_for(pilot, lambda: not panel.work.busy, 30, "work done")
            # idle: the panel closes and the screen asked for shows
            await pilot.press("f6")
            await wait_for(pilot, lambda: app.screen is app.base, 30, "panel closed")
            await wait_for(pilot, lambda: app.active_tab == "scenes", 30, "scenes shown")

    asyncio.run(scenario())


def test_the_synthesis_size_and_time_show_whole(plugins, tmp_path):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=SIZE) as pilot:
            panel = await _panel(app, pilot, plugins)
            panel.query_one("#gp-dataset", Input).value = str(tmp_path / "set")
            panel.query_one("#gp-subjects", Input).value = "1"
            panel.query_one("#gp-reps", Input).value = "1"
            await pilot.press("s")
            work = panel.work
            await wait_for(pilot, lambda: work.outcome is not None, 60, "estimate")
            asked = work.text
            assert asked.startswith("s again within"), asked

            def whole() -> bool:
                shown = re.sub(r"\s+", "", text_in(app, work))
                return re.sub(r"\s+", "", asked) in shown

            await wait_for(pilot, whole, 30, f"{asked!r} whole in {text_in(app, work)!r}")

    asyncio.run(scenario())
