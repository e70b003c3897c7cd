"""Issue 27 (fifth, b): the Gestures panel at 80 x 24 says a cancelled synthesis once,
on its work line (with what it left unchanged), and the next key's outcome replaces it."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines


def test_a_stopped_synthesis_is_said_once_and_goes(plugins, tmp_path):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            app.push_screen(plugins.of("panel")["gestures"].factory(app))
            await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel")
            panel = app.screen
            await wait_for(pilot, lambda: bool(panel.query("#gp-files")), 30, "composed")
            work = panel.work
            panel.query_one("#gp-dataset", Input).value = str(tmp_path / "set")
            panel.query_one("#gp-subjects", Input).value = "3"
            panel.query_one("#gp-reps", Input).value = "50"
            await pilot.press("s")
            await wait_for(pilot, lambda: work.outcome is not None, 60, "estimate")
            await pilot.press("s")
            await wait_for(pilot, lambda: work.busy, 30, "synthesis running")
            await pilot.press("x")
            await wait_for(pilot, lambda: work.outcome == "cancelled", 60, "cancelled")
            await pilot.pause(0.2)
            shown = " ".join(" ".join(screen_lines(app)).split())
            assert shown.count("cancelled") == 1, shown
            assert "cancelled: the dataset folder is unchanged" in shown, shown
            await pilot.press("x")  # the next key: its outcome replaces the line
            await wait_for(pilot, lambda: "nothing to cancel" in work.text, 10, "x again")
            shown = " ".join(" ".join(screen_lines(app)).split())
            assert "cancelled" not in shown, shown

    asyncio.run(scenario())
