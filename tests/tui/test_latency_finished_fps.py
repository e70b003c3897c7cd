"""The Latency screen (F7) after a demo ended: the finished run's camera line gives its
last numbers (frames a second over its whole run) or says the run ended, never
"counting ..." for a run that counts nothing any more."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_issue27_seventh_demo_end import FakeRun


def _finish(app, run) -> None:
    demos = app.session.demos
    demos.history.begin("knob")
    demos.run, demos.name, demos.state = run, "knob", "running"
    for _ in range(8):
        demos.poll()
    demos.run.stopped = True
    demos._ended("knob", "ended")
    demos.run = None


def test_a_finished_demo_s_camera_line_is_never_counting(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=(80, 24)) as pilot:
            _finish(app, FakeRun())
            head = app.query_one("#lat-head")
            await wait_for(pilot, lambda: "finished demo" in str(head.render()), 30, "kept")
            text = " ".join(str(head.render()).split())
            assert "counting" not in text, text
            # its whole run: 8 frames a poll over a quarter of a second a poll
            assert "32.0 fps delivered" in text, text

    asyncio.run(scenario())


class NoUptime(FakeRun):
    def snapshot(self) -> dict:
        snap = super().snapshot()
        del snap["uptime_s"]
        return snap


def test_a_finished_demo_without_its_time_says_it_ended(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=(80, 24)) as pilot:
            _finish(app, NoUptime())
            head = app.query_one("#lat-head")
            await wait_for(pilot, lambda: "finished demo" in str(head.render()), 30, "kept")
            text = " ".join(str(head.render()).split())
            assert "counting" not in text and "the run ended" in text, text

    asyncio.run(scenario())
