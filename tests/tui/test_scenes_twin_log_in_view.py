"""The Scenes screen (F6) after a demo stopped, at 80 x 24 and 120 x 40: the line saying
where the twin's outputs were recorded shows, its file's name whole, below the run's last
numbers however many lines they take (at 80 x 24 "what the twin's outputs received:" was
the last line on screen, its path below it)."""

from __future__ import annotations

import asyncio
from pathlib import Path

import pytest

from console.cli.main import Context
from console.plugin_api.runtime import Started
from console.session.demos import twin_log_path
from console.tui.app import HapTableApp
from console.tui.util import short_path

from .conftest import wait_for
from .test_camera_layout import SIZES, screen_lines
from .test_issue27_seventh_demo_end import FakeRun


class FlowRun(FakeRun):
    """A flow demo's process: its numbers, a flow played and a refusal after it."""

    def snapshot(self) -> dict:
        snap = super().snapshot()
        last = [
            {"parts": [{"actuator": "PA", "frequency_hz": 250.0}], "center_mm": (300.0, 200.0)},
            {"kind": "refused", "reason": "no resting hand under the cursor"},
        ]
        return {**snap, "flow": {"direction": "PA to PB", "flows": 3, "last": last}}


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_twin_log_line_shows_after_a_stopped_demo(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 30, "scenes")
            demos = app.session.demos
            demos.history.begin("flow")
            demos.run, demos.name, demos.state = FlowRun(), "flow", "running"
            app.session.emit(Started("demo", "flow", detail="running"))
            for _ in range(8):
                demos.poll()
            await wait_for(pilot, lambda: "flow PA to PB" in "\n".join(screen_lines(app)), 30, "on")
            log = twin_log_path("flow")
            demos.last_snapshot = demos.run.snapshot()
            demos.last_final = {"twin_log": str(log)}
            demos.run.stopped = True
            demos._ended("flow", "stopped")
            demos.run = None
            shown = lambda: "\n".join(screen_lines(app))  # noqa: E731
            await wait_for(pilot, lambda: "last run (stopped" in shown(), 30, "the last run")
            await pilot.pause(0.3)
            assert "twin" in shown() and Path(log).name in shown(), shown()
            # cut between whole names only (a second new operator's try read
            # `/tmp/newuser…/demo-…json`, names cut inside)
            line = next(ln for ln in screen_lines(app) if Path(log).name in ln)
            token = next(w for w in line.split() if Path(log).name in w)
            names = set(str(log).split("/")) | set(short_path(str(log)).split("/"))
            cut = [n for n in token.split("/") if n not in names and n != "…"]
            assert not cut, (cut, line)
            assert "no resting hand" in shown(), shown()  # the run's numbers above it too

    asyncio.run(scenario())


def test_whole_names_cuts_a_path_between_its_names_only():
    from console.tui.path_field import whole_names  # lazy: beside the screen's test

    path = "/tmp/newuser-abc123/state/haptable/demo-8098-flow-20261130-124113.json"
    assert whole_names(path, len(path)) == path
    assert whole_names(path, 49) == "/tmp/…/demo-8098-flow-20261130-124113.json"
    assert whole_names(path, 60) == "/tmp/newuser-abc123/…/demo-8098-flow-20261130-124113.json"
    assert whole_names(path, 30) is None  # its file's name alone does not fit
