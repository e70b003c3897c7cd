"""The Scenes screen after the operator's e-stop reset (issue 27, third new-user try):
the words that said the e-stop is active go, the knob's state says what is true now;
the demo's status names the camera's rate apart from the rate its loop reads."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.plugin_api.runtime import Stopped
from console.tui.app import HapTableApp

from .conftest import wait_for


def _screen(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def test_the_reset_replaces_what_the_estop_said(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 30, "e-stopped")
            # the knob, stopped by the e-stop (as the session reports a running demo's end)
            error = "e-stop active (operator e-stop (console)); reset it first"
            app.session.demos.last_snapshot = {"demo": "knob", "last_error": error}
            app.session.emit(Stopped("demo", "knob", reason="e-stopped"))
            await wait_for(pilot, lambda: "reset it first" in _screen(app), 30, "last run")
            table = app.query_one("#demo-table")
            state = lambda: str(table.get_cell("knob", "state"))  # noqa: E731
            await wait_for(pilot, lambda: state() == "e-stopped", 30, "knob e-stopped")
            await pilot.press("d")
            await wait_for(pilot, lambda: app.focused is table, 30, "demo table")
            table.move_cursor(row=1)  # knob
            await pilot.press("enter")
            await wait_for(pilot, lambda: "e-stop is active" in _screen(app), 30, "refused")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 30, "reset")
            await wait_for(pilot, lambda: "e-stop is active" not in _screen(app), 30, "gone")
            screen = _screen(app)
            assert "demo knob: the e-stop is reset; enter starts it again" in screen
            assert "e-stop active" not in screen and "reset it first" not in screen
            assert "last run (e-stopped)" in screen  # how it ended: still true
            assert state() == "stopped"

    asyncio.run(scenario())


def test_the_demo_status_names_the_camera_rate_and_the_loop_rate():
    from textual.content import Content

    from plugins.demos.status import status_lines

    snap = {
        "demo": "knob",
        "running": True,
        "camera": {"fps": 52.0, "nominal_fps": 60.0, "rate_fps": None},
        "latency": {"fps": 52.0, "dropped_camera": 2, "dropped_queue": 0, "stages": {}},
    }
    text = Content.from_markup("\n".join(status_lines(snap))).plain
    assert "camera set to 60 fps" in text and "loop 52 fps" in text
