"""A new operator's try, finding 16d (Scenes, 80 x 24): a cancelled demo start said it
twice, ``demo knob cancelled`` on the work line and ``knob cancelled`` in the demo status
under it. The work line says it; the status says only that there are no numbers."""

from __future__ import annotations

import asyncio
import threading

from textual.widgets import DataTable

from console.cli.main import Context
from console.plugin_api.runtime import Started, Stopped
from console.tui.app import HapTableApp

from .conftest import wait_for


def _screen(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def test_a_cancelled_start_is_said_once(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            table = app.query_one("#demo-table", DataTable)
            lw = app.query_one("#demo-work")
            app.session.demos.last_snapshot = None  # no run before: no numbers to show
            gone = threading.Event()

            def job(progress, cancelled):
                while not cancelled():
                    gone.wait(0.05)
                raise RuntimeError("cancelled")

            lw.start("demo knob", job)
            app.session.emit(Started("demo", "knob", detail="starting"))
            await wait_for(pilot, lambda: "knob starting" in _screen(app), 30, "starting")
            await pilot.press("x")
            await wait_for(pilot, lambda: not lw.busy, 30, "cancelled")
            app.session.emit(Stopped("demo", "knob", reason="cancelled"))
            state = lambda: str(table.get_cell("knob", "state"))  # noqa: E731
            await wait_for(pilot, lambda: state() == "cancelled", 30, "knob cancelled")
            await pilot.pause(0.2)
            shown = _screen(app)
            assert "demo knob cancelled" in shown
            below_table = shown.split("demo knob cancelled", 1)[1]
            assert "cancelled" not in below_table.replace("demo knob cancelled", ""), shown
            assert shown.count("knob cancelled") == 1, shown

    asyncio.run(scenario())
