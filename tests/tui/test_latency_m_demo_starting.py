"""Issue 27, F7 Latency's ``m`` with a real knob demo at 80 x 24. Pressed while the demo
started (Enter on Scenes, then F7 ``m``), ``m`` began a camera measurement the demo was
taking the camera from: the head said ``measuring: 10 s left`` and, once the demo ran,
nothing said what became of it. It says the demo is starting and that its own loop shows
here once it runs; once it runs, ``m`` says its loop is measured, drawn at once."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines


def _screen(app) -> str:
    return " ".join(" ".join(screen_lines(app)).split())


def test_m_while_the_knob_demo_starts_and_runs(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("f7")  # Latency built and shown once before the demo
            await wait_for(pilot, lambda: app.pane("latency") is not None, 20, "latency")
            await pilot.press("f6")
            await wait_for(pilot, lambda: app.focused is not None, 10, "focus")
            await pilot.press("d")
            table = app.query_one("#demo-table")
            await wait_for(pilot, lambda: app.focused is table, 10, "the demos")
            names = [str(table.get_row_at(i)[0]) for i in range(table.row_count)]
            table.move_cursor(row=names.index("knob"))
            await pilot.press("enter")
            demos = app.session.demos
            await wait_for(pilot, lambda: demos.state == "starting", 20, "starting")
            await pilot.press("f7", "m")
            said = "m: demo knob is starting; its own loop shows here once it runs"
            await wait_for(pilot, lambda: said in _screen(app), 10, _screen(app))
            assert "measuring:" not in _screen(app), _screen(app)
            await wait_for(pilot, lambda: demos.state == "running", 60, "running")
            await wait_for(pilot, lambda: said not in _screen(app), 10, "no longer starting")
            await wait_for(pilot, lambda: "demo knob loop" in _screen(app), 20, "its loop")
            await pilot.press("m")
            runs = "m: demo knob runs; its own loop is measured below"
            await wait_for(pilot, lambda: runs in _screen(app), 5, _screen(app))
            assert "measuring:" not in _screen(app), _screen(app)
            await asyncio.to_thread(demos.stop)

    asyncio.run(scenario())
