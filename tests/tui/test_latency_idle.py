"""The Latency screen starts nothing of its own: it shows the loop that runs (a demo's,
the camera's while Camera keeps it), and ``m`` runs the camera loop for a while."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.panes import latency

from .conftest import wait_for


def _head(app) -> str:
    return str(app.query_one("#lat-head").render())


def test_latency_alone_runs_no_camera_loop_and_m_measures_for_a_while(plugins, monkeypatch):
    monkeypatch.setattr(latency, "MEASURE_S", 3.0)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: "m measures" in _head(app), 20, "the idle hint")
            await asyncio.sleep(1.0)
            svc = app.session.camera_started
            assert svc is None or not svc.running  # opening the screen started nothing
            await pilot.press("m")
            table = app.query_one("#lat-table")
            # said while it runs (on a loaded machine the rows may come after its 3 s)
            await wait_for(pilot, lambda: "measuring" in _head(app), 10, "measuring")
            await wait_for(pilot, lambda: table.row_count >= 2, 30, "the loop's rows")
            await wait_for(pilot, lambda: not app.session.camera_started.running, 30, "stop")
            await wait_for(pilot, lambda: "last numbers" in _head(app), 10, "kept numbers")
            assert table.row_count >= 2  # the numbers measured stay on screen

    asyncio.run(scenario())
