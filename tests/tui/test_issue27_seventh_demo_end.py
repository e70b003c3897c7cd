"""Issue 27, seventh new-user try, findings 2, 3 and 6: a watchdog e-stop is said as one
from its first moment, the Latency screen keeps the finished demo's numbers (its whole
run in the sparklines) and every demo run gets its own twin log."""

from __future__ import annotations

import asyncio
import re

from console.cli.main import Context
from console.plugin_api.runtime import Started, Stopped
from console.session.demos import twin_log_path
from console.tui.app import HapTableApp

from .conftest import wait_for

WHY = (
    "runtime watchdog: frame loop stalled 256 ms in camera (no frame arriving) "
    "(limit [runtime] watchdog_ms = 250); outputs silenced"
)


def _screen(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


class FakeRun:
    """A demo process as the session polls it: numbers that change each poll."""

    def __init__(self) -> None:
        self.n, self.stopped, self.scene_name, self.camera = 0, False, "flow_hand", None

    def snapshot(self) -> dict:
        self.n += 1
        stage = {"p50_ms": 1.0 + self.n % 5, "p99_ms": 9.0, "max_ms": 12.0}
        lat = {"stages": {"vision": stage, "classify": stage}, "end_to_end": stage}
        lat.update(fps=30.0, frames=self.n * 8, dropped_queue=0, errors=0)
        return {
            "demo": "flow",
            "running": True,
            "uptime_s": self.n / 4,
            "watchdog": {"limit_ms": 250.0, "tripped": False, "reason": None},
            "camera": {"driver": "twin", "fps": 60.0},
            "latency": lat,
        }


def test_a_watchdog_estop_is_said_at_once_and_its_run_numbers_stay(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 30, "scenes")
            demos, work = app.session.demos, app.query_one("#demo-work")
            demos.history.begin("flow")
            demos.run, demos.name, demos.state = FakeRun(), "flow", "running"
            app.session.emit(Started("demo", "flow", detail="running"))
            for _ in range(60):  # 15 s of polls while the Latency screen never showed
                demos.poll()
            await wait_for(pilot, lambda: "watchdog ok" in _screen(app), 30, "running")
            app.session.emit(Stopped("estop", reason=WHY))  # the table's e-stop, first
            app.session.emit(Started("demo", "flow", detail="stopping"))
            want = "e-stop by the watchdog (frame loop stalled 256 ms"
            await wait_for(pilot, lambda: want in work.text, 30, "e-stop on the demo line")
            await wait_for(pilot, lambda: want in _screen(app), 30, "e-stop in its status")
            assert "watchdog ok" not in _screen(app)  # never a normal stop, never "ok"
            demos.run.stopped = True
            demos._ended("flow", "e-stopped")
            demos.run = None
            await wait_for(
                pilot, lambda: "last run (e-stop by the watchdog" in _screen(app), 30, "end"
            )
            assert "watchdog ok" not in _screen(app)
            await pilot.press("f7")
            head = app.query_one("#lat-head")
            await wait_for(pilot, lambda: "finished demo flow" in str(head.render()), 30, "kept")
            assert re.search(r"it ended at \d\d:\d\d:\d\d", str(head.render()))
            table = app.query_one("#lat-table")
            await wait_for(pilot, lambda: table.row_count >= 3, 30, "its stages")
            labels = [str(table.get_row_at(i)[0]) for i in range(table.row_count)]
            row = labels.index("vision")
            # its whole run, one bar per poll (not the 16 seen), once the table has its width
            polls = len(demos.history.values("vision"))  # 60 and the app's own polls
            assert polls >= 60
            spark = lambda: str(table.get_row_at(row)[5])  # noqa: E731
            # (stretched over the row's width: at least a bar per poll)
            await wait_for(pilot, lambda: len(spark()) >= polls, 30, "the whole run")
            assert str(table.get_row_at(labels.index("vision"))[2]) == "9.00"

    asyncio.run(scenario())


def test_each_demo_run_gets_its_own_twin_log():
    paths = {twin_log_path("flow") for _ in range(3)}
    assert len(paths) == 3  # started within one second: none overwrites another
    assert all(re.search(r"demo-\d+-flow-\d{8}-\d{6}(-\d+)?\.json$", str(p)) for p in paths)
