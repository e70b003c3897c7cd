"""The Scenes screen says what is true (issue 27): ``x`` while a demo starts cancels it
(nothing left running, its outputs silent) in the demo's own words; a running flow's
status fits 80 x 24 with the keys under it; the hand the operator placed on the twin is
shown where it moved."""

from __future__ import annotations

import asyncio
import threading
from types import SimpleNamespace

from console.cli.main import Context
from console.plugin_api.runtime import Snapshot
from console.tui.app import HapTableApp

from .conftest import wait_for


def _screen(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def _work(app) -> str:
    return app.query_one("#demo-work").text


def test_x_while_the_demo_comes_up_cancels_it(plugins, monkeypatch):
    """The start's last moment (its process runs, the console has not said so yet): x
    is taken, so the demo must not run on."""
    from console.runtime import demo_process

    came_up, x_pressed = threading.Event(), threading.Event()
    wait_started = demo_process.DemoProcess.wait_started

    def slow_to_say(self, *a, **kw):
        wait_started(self, *a, **kw)
        came_up.set()
        x_pressed.wait(30)

    monkeypatch.setattr(demo_process.DemoProcess, "wait_started", slow_to_say)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            demos = app.session.demos
            demos.last_final = {"twin_log": "/run/demo-1-flow.json"}  # an earlier flow's
            await pilot.press("d")
            table = app.query_one("#demo-table")
            await wait_for(pilot, lambda: app.focused is table, 30, "demo table")
            table.move_cursor(row=1)  # knob
            await pilot.press("enter")
            await wait_for(pilot, came_up.is_set, 60, "knob process up")
            run = demos.run
            await pilot.press("x")
            x_pressed.set()
            await wait_for(pilot, lambda: "cancelled" in _work(app), 30, "cancelled")
            await wait_for(pilot, lambda: demos.run is None, 30, "nothing runs")
            state = lambda: str(table.get_cell("knob", "state"))  # noqa: E731
            await wait_for(pilot, lambda: state() == "cancelled", 30, "cancelled in the table")
            assert _work(app) == "demo knob cancelled"
            assert run.proc.wait(10) is not None  # its process ended
            gate = run.final["final"]["outputs"]["gate"]
            assert gate["level_v"] == [0.0, 0.0] and gate["relays_closed"] == []
            status = str(app.query_one("#demo-status").render())
            assert "flow.json" not in status and "last run (cancelled)" in status
            assert "knob" in status
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs back")
            assert not app.session.outputs.estopped

    asyncio.run(scenario())


#: a running flow's status at 80 columns, as the twin's demo reports it
FLOW_LINES = [
    "flow running 12 s  watchdog ok (250 ms)",
    "camera set to 60 fps, loop 48 fps, dropped 266 (camera) + 0 (queue)",
    "latency p50/p99 ms: capture 24/82  vision 4.2/10  classify 0.3/0.7  scene 0.0/0.1  "
    "effect 0.1/0.1  output 0.6/0.6  end to end 5.5/5.5",
    "hand resting at 543,181 mm, 0 contacts, gesture static_hand",
    "flow right: 3 played; last at 540,180 mm: PC 241 Hz + PALL 134 Hz",
    "preparing every flow on the grid (atlas): 2 % (36/1296), about 6 min left; a hand "
    "elsewhere gets its flow planned when asked (1-3 s)",
]


def _twin_demo(app, monkeypatch) -> list:
    """The flow demo as running on the twin (its status lines, a touchable camera)."""
    import plugins.demos.panel as panel

    targets: list = []
    demos = app.session.demos
    monkeypatch.setattr(panel, "status_lines", lambda snap: FLOW_LINES)
    monkeypatch.setattr(demos, "touchable", lambda: SimpleNamespace(set_target=targets.append))
    return targets


def test_a_running_flow_fits_and_the_placed_hand_follows_the_arrows(plugins, monkeypatch):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 30, "scenes")
            targets = _twin_demo(app, monkeypatch)
            app.session.emit(Snapshot("demo", "flow", data={"demo": "flow", "running": True}))
            await wait_for(pilot, lambda: "twin:" in _screen(app), 30, "status shown")
            screen = _screen(app)
            assert "space puts your finger on the twin" in screen  # the flow's last line, whole
            assert "demos (d): enter start/stop" in screen  # and the keys under it
            await pilot.press("space")
            await wait_for(pilot, lambda: "your finger on the twin at" in _work(app), 30, "placed")
            x, y = app.pane("scenes").hand_mm
            await pilot.press("down")
            await wait_for(pilot, lambda: f"{x:.0f},{y + 20:.0f} mm" in _work(app), 30, "moved")
            assert "hand placed" not in _work(app)
            await wait_for(pilot, lambda: (x, y + 20) in targets, 30, "the twin got it")
            app.session.emit(Snapshot("demo", "flow", data={"demo": "flow", "running": True}))
            want = f"your finger on the twin at {x:.0f},{y + 20:.0f} mm"
            await wait_for(pilot, lambda: want in _screen(app), 30, "finger line on screen")

    asyncio.run(scenario())
