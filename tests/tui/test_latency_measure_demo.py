"""The Latency screen's ``m`` while a demo runs (issue 27): one line says that the demo's
own loop is what is measured, and where; the line goes when the demo stops."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for

SNAP = {
    "demo": "knob",
    "camera": {"driver": "twin", "fps": 60.0, "dropped": 0},
    "latency": {
        "fps": 60.0,
        "frames": 120,
        "dropped_queue": 0,
        "errors": 0,
        "stages": {"vision": {"p50_ms": 4.0, "p99_ms": 6.0, "max_ms": 7.0}},
        "end_to_end": {"p50_ms": 5.0, "p99_ms": 7.0, "max_ms": 8.0},
    },
}


class FakeRun:
    """A demo process as the Latency screen reads it (its name and snapshots)."""

    name = "knob"

    def snapshot(self) -> dict:
        return SNAP


def _screen(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def test_m_while_a_demo_runs_says_its_loop_is_measured(plugins, monkeypatch):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("latency")
            run = {"now": FakeRun()}
            monkeypatch.setattr(pane, "demo_run", lambda: run["now"])
            await wait_for(pilot, lambda: "demo knob loop" in _screen(app), 30, "demo shown")
            await pilot.press("m")
            said = "m: demo knob runs; its own loop is measured above (F6, s stops it)"
            await wait_for(pilot, lambda: said in _screen(app), 30, "m's outcome")
            svc = app.session.camera_started
            assert svc is None or not svc.running  # no camera loop of its own
            run["now"] = None  # the demo stopped: what m was told is past
            await wait_for(pilot, lambda: "m: demo" not in _screen(app), 30, "line gone")

    asyncio.run(scenario())
