"""The Scenes screen while a demo starts and stops (issue 27, fourth new-user try): every
line says starting or stopping (no "stopped 0 s" while it starts, no "running" while it
stops); an e-stop pressed while it stopped does not rename the operator's stop; the
operator's finger on the twin has one name; at 80 x 24 the scenes stay reachable and the
flow's preparation line stays on screen."""

from __future__ import annotations

import asyncio
import threading

from console.cli.main import Context
from console.plugin_api.runtime import Snapshot, Started
from console.runtime.demo_process import DemoProcess
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on


def _screen(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def _work(app) -> str:
    """The demos' status line."""
    return app.query_one("#demo-work").text


def _state(app, name: str) -> str:
    return str(app.query_one("#demo-table").get_cell(name, "state"))


def _gated(monkeypatch, obj, attr: str) -> threading.Event:
    """``obj.attr`` waits for the returned event before it does its work."""
    gate, real = threading.Event(), getattr(obj, attr)

    def held(*a, **kw):
        gate.wait(60)
        return real(*a, **kw)

    monkeypatch.setattr(obj, attr, held)
    return gate


async def _start_knob(app, pilot):
    await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
    await pilot.press("d")
    table = app.query_one("#demo-table")
    await wait_for(pilot, lambda: app.focused is table, 30, "demo table focused")
    table.move_cursor(row=[str(table.get_row_at(i)[0]) for i in range(2)].index("knob"))
    await pilot.press("enter")


def test_a_starting_and_a_stopping_demo_say_so_on_every_line(plugins, monkeypatch):
    start_gate = _gated(monkeypatch, DemoProcess, "wait_started")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await _start_knob(app, pilot)
            await wait_for(pilot, lambda: _state(app, "knob") == "starting", 30, "starting")
            await wait_for(pilot, lambda: app.session.demos.run is not None, 30, "process")
            await pilot.pause(1.0)  # the console polls the starting demo meanwhile
            status = words_on(app, "#demo-status")
            assert "stopped" not in status and "0 fps" not in status, status
            assert "knob starting" in status
            start_gate.set()
            await wait_for(pilot, lambda: "running" in _state(app, "knob"), 60, "running")
            # the operator's finger on the twin: one name on every line
            await pilot.press("space")
            await wait_for(pilot, lambda: "finger" in _work(app), 30, "put")
            assert "your finger on the twin at" in _work(app)
            await wait_for(  # the status follows; the position is said once (the line)
                pilot, lambda: "space puts your finger" not in words_on(app, "#demo-status"), 30
            )
            assert "your finger on the twin at" not in words_on(app, "#demo-status")
            stop_gate = _gated(monkeypatch, app.session.demos, "_stop_run")
            await pilot.press("s")
            await wait_for(pilot, lambda: _state(app, "knob") == "stopping", 30, "stopping")
            await pilot.pause(1.0)  # snapshots keep coming while it stops
            work, status = _work(app), words_on(app, "#demo-status")
            assert "demo knob stopping" in work and "running" not in work, work
            assert status.startswith("knob stopping") and "running" not in status, status
            assert "your finger" not in status  # the twin cannot be touched any more
            stop_gate.set()
            await wait_for(pilot, lambda: _state(app, "knob") == "stopped", 30, "stopped")

    asyncio.run(scenario())


def test_an_estop_while_the_demo_stops_does_not_rename_the_stop(plugins, monkeypatch):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await _start_knob(app, pilot)
            await wait_for(pilot, lambda: "running" in _state(app, "knob"), 60, "running")
            stop_gate = _gated(monkeypatch, app.session.demos, "_stop_run")
            await pilot.press("s")
            await wait_for(pilot, lambda: _state(app, "knob") == "stopping", 30, "stopping")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 30, "e-stopped")
            await pilot.pause(1.0)  # the demo's process hears the e-stop
            stop_gate.set()
            await wait_for(pilot, lambda: app.session.demos.run is None, 30, "ended")
            await wait_for(pilot, lambda: "last run" in _screen(app), 30, "last run")
            screen = " ".join(_screen(app).split())
            assert _state(app, "knob") == "stopped"
            assert "last run (stopped by s; an e-stop came after)" in screen, screen
            assert "demo knob stopped by s; an e-stop came after: ctrl+r resets it" in screen
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 30, "reset")
            await wait_for(pilot, lambda: "ctrl+r resets" not in _screen(app), 30, "gone")
            screen = " ".join(_screen(app).split())
            assert "demo knob stopped by s; the e-stop after it is reset" in screen, screen
            assert "e-stopped" not in screen

    asyncio.run(scenario())


def _flow_snapshot() -> dict:
    last = {
        "kind": "flow",
        "center_mm": [540.0, 180.0],
        "parts": [
            {"actuator": "PC", "frequency_hz": 241.0},
            {"actuator": "PALL", "frequency_hz": 134.0},
        ],
        "late_s": 0.817,
    }
    ms = {"p50_ms": 56.0, "p99_ms": 77.0}
    prep = {"what": "every flow on the grid (atlas)", "done": 26, "total": 1296, "left_s": 540}
    return {
        "demo": "flow",
        "running": True,
        "uptime_s": 12.0,
        "watchdog": {"limit_ms": 250.0},
        "camera": {"rate_fps": 60.0},
        "latency": {
            "fps": 38.0,
            "dropped_camera": 283,
            "dropped_queue": 0,
            "stages": {k: ms for k in ("vision", "classify", "scene", "effect", "scheduled")},
            "capture_to_arrival": ms,
            "end_to_end": ms,
        },
        "hand": {"hands": 1, "rest_mm": [544.0, 183.0], "contacts": 0, "gesture": "static"},
        "flow": {"direction": "right", "flows": 1, "last": [last], "preparing": prep},
    }


def test_at_80x24_a_running_flow_leaves_the_scenes_and_its_preparation_in_view(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 30, "scenes pane")
            app.session.emit(Started("demo", "flow", detail="running"))
            app.session.emit(Snapshot("demo", "flow", data=_flow_snapshot()))
            await wait_for(pilot, lambda: "flow right" in _screen(app), 30, "the flow block")
            await pilot.pause(0.5)
            lines = _screen(app).splitlines()
            table = app.query_one("#scene-table")
            cursor = str(table.get_row_at(table.cursor_row)[0])
            assert any(ln.split()[:1] == [cursor] for ln in lines), "\n".join(lines)
            text = "\n".join(lines)
            assert "preparing every flow on the grid (atlas): 2 %" in text, text
            assert "about 9 min left" in text
            assert not any(ln.lstrip().startswith("817 ms") for ln in lines), text  # unwrapped
            await pilot.press("down", "down", "down")  # the scenes scroll to the cursor
            cursor = str(table.get_row_at(table.cursor_row)[0])
            assert cursor != "alignment"
            assert any(ln.split()[:1] == [cursor] for ln in _screen(app).splitlines())

    asyncio.run(scenario())
