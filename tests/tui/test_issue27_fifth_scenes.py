"""The Scenes screen and the log view at 80 x 24 (issue 27, fifth new-user try): a
demo e-stopped by its own watchdog says why, whole, on the screen and in the log; a
running demo has no progress bar or "starting" line left; a cancelled start says
"cancelling" on its row; a number is never cut; the log view loses no character where
its lines wrap."""

from __future__ import annotations

import asyncio
import logging
import re
import threading

from textual.widgets import DataTable, RichLog

from console.cli.main import Context
from console.plugin_api.runtime import Started, Stopped
from console.tui.app import HapTableApp
from console.tui.logs import ViewHandler

from .conftest import wait_for

WATCHDOG = (
    "runtime watchdog: frame loop stalled 412 ms in vision "
    "(limit [runtime] watchdog_ms = 250); outputs silenced"
)


def _screen(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def _flat(text: str) -> str:
    """``text`` without spaces, line ends and the log view's border."""
    return "".join(text.replace("█", "").split())


def test_scenes_say_one_state_and_the_watchdog_reason_whole(plugins, caplog):
    caplog.set_level(logging.INFO)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        view = ViewHandler(app)  # the log view's lines (``capture_logs`` in the console)
        logging.getLogger().addHandler(view)
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            pane = app.pane("scenes")
            table = app.query_one("#demo-table", DataTable)
            state = lambda name: str(table.get_cell(name, "state"))  # noqa: E731
            lw = app.query_one("#demo-work")
            # the knob starts (its progress at 5 %), then runs: one state everywhere
            app.session.emit(Started("demo", "knob", detail="starting"))
            await wait_for(pilot, lambda: state("knob") == "starting", 30, "starting")
            lw.show("demo knob: opening the camera", 0.05)
            app.session.emit(Started("demo", "knob"))
            await wait_for(pilot, lambda: state("knob") == "running", 30, "running")
            await pilot.pause()
            assert lw.progress is None and "starting" not in _screen(app)
            app.session.emit(Stopped("demo", "knob", reason="stopped"))
            await wait_for(pilot, lambda: state("knob") == "stopped", 30, "knob stopped")
            # the flow starts; x cancels it: its row says so at once
            gone = threading.Event()

            def job(progress, cancelled):
                while not cancelled():
                    gone.wait(0.05)
                raise RuntimeError("cancelled")

            lw.start("demo flow", job)
            app.session.emit(Started("demo", "flow", detail="starting"))
            await wait_for(pilot, lambda: state("flow") == "starting", 30, "flow starting")
            await pilot.press("x")
            await wait_for(pilot, lambda: state("flow") == "cancelling", 30, "cancelling")
            assert "flow starting" not in _screen(app)
            await wait_for(pilot, lambda: not lw.busy, 30, "cancelled")
            app.session.emit(Stopped("demo", "flow", reason="cancelled"))
            await wait_for(pilot, lambda: state("flow") == "cancelled", 30, "flow cancelled")
            # the flow runs, its watchdog e-stops it: the reason whole, numbers whole
            app.session.demos.last_snapshot = {
                "demo": "flow",
                "running": True,
                "uptime_s": 12.0,
                "watchdog": {"limit_ms": 250},
                "camera": {"fps": 60.0},
                "latency": {"fps": 60.0, "dropped_camera": 36120, "dropped_queue": 4077},
            }
            app.session.emit(Stopped("estop", reason=WATCHDOG))
            app.session.emit(Stopped("demo", "flow", reason="e-stopped"))
            await wait_for(pilot, lambda: state("flow") == "e-stopped", 30, "e-stopped")
            await wait_for(pilot, lambda: "why below" in _screen(app), 30, "said")
            screen = _screen(app)  # said as the watchdog's e-stop (seventh try), whole
            said = "e-stop by the watchdog (" + WATCHDOG.removeprefix("runtime watchdog: ")
            assert _flat(said) in _flat(screen), screen
            assert re.search(r"\d…", screen) is None, screen  # fields drop, numbers whole
            assert any(_flat(said) in _flat(r.getMessage()) for r in caplog.records)
            assert pane is not None
            # the log view shows the reason whole where its lines wrap
            view.lines.extendleft(f"earlier line {i}" for i in range(30))  # a scrollbar
            await pilot.press("ctrl+l")
            await wait_for(pilot, lambda: app.screen.query(RichLog), 30, "log view")
            await pilot.pause()
            assert _flat(said) in _flat(_screen(app)), _screen(app)
            log = app.screen.query_one(RichLog)  # no line wider than the view (cut)
            shown = log.scrollable_content_region.width
            assert max(line.cell_length for line in log.lines) <= shown, shown

    try:
        asyncio.run(scenario())
    finally:
        for h in list(logging.getLogger().handlers):
            if isinstance(h, ViewHandler):
                logging.getLogger().removeHandler(h)
