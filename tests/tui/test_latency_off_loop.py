"""Latency (F7) and Scenes (F6) count the flows a demo planned outside its frame loop
alike: Scenes said `2 played (1 once planned, not in Latency's frames)` while Latency
said nothing of that flow (its end to end counts only the frames whose decision scheduled
an output). Latency now has a row for them, `planned off loop`: how many and their
planning time, the line under the table saying what it counts, in Scenes' words."""

from __future__ import annotations

import asyncio
import threading
from types import SimpleNamespace

import numpy as np
import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.core.types import OutputPlan, Segment
from console.core.words import OFF_LOOP
from console.signals.waveforms import tone
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on

FS = 48000


class _Outputs:
    def play(self, plan, wait=False):
        return SimpleNamespace(done=threading.Event())


def _flow_state(profile, plugins) -> dict:
    """The flow demo's part of its snapshot after three plays, one of them planned off
    the frame loop in 0.3 s (as ``DemoRun.snapshot`` adds it)."""
    from plugins.demos.flow import FlowDemo
    from plugins.demos.run import demo_state

    demo = FlowDemo(profile, plugins, _Outputs(), plans=None, prepare=False)
    sig = tone(250, 10, 0.05, FS, 0.01)
    plan = OutputPlan(FS, (Segment(sig, np.zeros_like(sig), frozenset({"PA"})),))
    frame = SimpleNamespace(seq=1, stamps_s={"arrival": 0.0})
    for late_s in (0.0, 0.3, 0.0):
        demo._play(plan, (100.0, 100.0), "right", (100.0, 100.0), frame, late_s=late_s)
    return demo_state(demo)


class _FlowRun:
    """A flow demo process as the session polls it, its snapshot's demo part real."""

    def __init__(self, state: dict) -> None:
        self.stopped, self.scene_name, self.camera, self.n = False, "flow_hand", None, 0
        self.state = state

    def snapshot(self) -> dict:
        self.n += 1
        stage = {"p50_ms": 2.0, "p99_ms": 9.0, "max_ms": 12.0, "n": 2}
        lat = {"stages": {"vision": stage, "scheduled": stage}, "end_to_end": stage}
        lat.update(fps=30.0, frames=40 + self.n, dropped_queue=0, errors=0)
        return {
            "demo": "flow",
            "running": True,
            "uptime_s": self.n / 4,
            "watchdog": {"limit_ms": 250.0, "tripped": False, "reason": None},
            "camera": {"driver": "twin", "fps": 60.0},
            "latency": lat,
            **self.state,
        }

    def status_lines(self, snap: dict) -> list[str]:
        from plugins.demos.status import status_lines

        return status_lines(snap)


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_latency_counts_the_flows_planned_off_the_loop_as_scenes_does(profile, plugins, size):
    from plugins.demos.status import _flow_text

    state = _flow_state(profile, plugins)
    scenes = _flow_text(state["flow"])
    assert f"3 played (1 {OFF_LOOP}, not in Latency's end to end)" in scenes, scenes

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=size) as pilot:
            demos = app.session.demos
            demos.history.begin("flow")
            demos.run, demos.name, demos.state = _FlowRun(state), "flow", "running"
            demos.poll()
            table = app.query_one("#lat-table", DataTable)

            def rows() -> dict[str, list[str]]:
                got = [table.get_row_at(i) for i in range(table.row_count)]
                return {str(r[0]): [str(c) for c in r] for r in got}

            await wait_for(pilot, lambda: "planned off loop" in rows(), 20, "its row")
            late = rows()["planned off loop"]
            assert late[1:5] == ["300.00", "300.00", "300.00", "1"], late  # ms, how many
            assert "end to end" in rows(), rows()
            key = words_on(app, "#lat-key")
            assert f"planned off loop: 1 flow {OFF_LOOP} (as Scenes counts them)" in key, key
            assert "end to end counts none of them" in key, key
            demos.run.stopped = True  # the finished run's numbers keep the row
            demos._ended("flow", "ended")
            demos.run = None
            head = lambda: words_on(app, "#lat-head")  # noqa: E731
            await wait_for(pilot, lambda: "finished demo" in head(), 20, "the finished run")
            assert rows()["planned off loop"][4] == "1", rows()

    asyncio.run(scenario())
