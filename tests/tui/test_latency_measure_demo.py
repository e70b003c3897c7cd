"""The Latency screen's ``m`` while a demo runs (issue 27): one line says that the demo's
own loop is what is measured, and where; the line goes when the demo stops."""

from __future__ import annotations

import asyncio

import pytest

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


def pane_text(app) -> str:
    """The audio line's words (it shows once the outputs are open)."""
    return str(app.query_one("#lat-audio").render())


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
            said = "m: demo knob runs; its own loop is measured below (F6, s stops it)"
            await wait_for(pilot, lambda: said in _screen(app), 30, "m's outcome")
            svc = app.session.camera_started
            assert svc is None or not svc.running  # no camera loop of its own
            run["now"] = None  # the demo stopped: what m was told is past
            await wait_for(pilot, lambda: "m: demo" not in _screen(app), 30, "line gone")

    asyncio.run(scenario())


#: a flow demo's snapshot: every stage a row (the table as tall as it gets)
FLOW = {
    "demo": "flow",
    "camera": {"driver": "twin", "fps": 60.0, "dropped": 0},
    "latency": {
        "fps": 60.0,
        "frames": 1006,
        "dropped_queue": 0,
        "errors": 0,
        "capture_to_arrival": {"p50_ms": 1.0, "p99_ms": 2.0, "max_ms": 3.0, "n": 1006},
        "stages": {
            s: {"p50_ms": 4.0, "p99_ms": 6.0, "max_ms": 7.0, "n": 1006}
            for s in ("vision", "classify", "scene", "effect", "scheduled")
        },
        "end_to_end": {"p50_ms": 5.0, "p99_ms": 7.0, "max_ms": 8.0, "n": 40},
    },
}


class FlowRun(FakeRun):
    name = "flow"

    def snapshot(self) -> dict:
        return FLOW


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_ms_answer_is_on_screen_while_a_demo_runs(plugins, monkeypatch, size):
    """A new operator's try at 80 x 24 (flow demo, F7, m): the answer was under a table
    as tall as a flow demo's, below the screen; it is under the head, in view."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=size) as pilot:
            pane = app.pane("latency")
            monkeypatch.setattr(pane, "demo_run", lambda: FlowRun())
            await wait_for(pilot, lambda: "end to end" in _screen(app), 30, "the table")
            await wait_for(pilot, lambda: "output latency" in pane_text(app), 30, "audio")
            await pilot.press("m")
            said = "m: demo flow runs; its own loop is measured below"
            await wait_for(pilot, lambda: said in " ".join(_screen(app).split()), 10, "m")
            rows = _screen(app).split("\n")
            at = next(i for i, r in enumerate(rows) if r.startswith("m: demo flow"))
            table = next(i for i, r in enumerate(rows) if r.split()[:2] == ["stage", "p50"])
            assert at < table, "\n".join(rows)  # however tall the table grows

    asyncio.run(scenario())
