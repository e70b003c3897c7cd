"""Issue 27 (Scenes, 80 x 24): the operator's finger on the twin is placed and moved
with its position said once on the screen (not on the demo's line and again in its
status block), and the hand line counts "1 contact" / "2 contacts"."""

from __future__ import annotations

import asyncio
import re

from console.cli.main import Context
from console.plugin_api.runtime import Snapshot, Started
from console.tui.app import HapTableApp
from plugins.demos.status import status_lines

from .conftest import wait_for


def _screen(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def _snap(contacts: int, rest_mm=(600.0, 200.0)) -> dict:
    return {
        "demo": "flow",
        "running": True,
        "uptime_s": 3.0,
        "watchdog": {"limit_ms": 250},
        "camera": {"fps": 60.0},
        "latency": {"fps": 60.0},
        "hand": {"hands": 1, "rest_mm": list(rest_mm), "contacts": contacts},
    }


def test_contacts_and_crossings_are_counted_in_words():
    one = "\n".join(status_lines(_snap(1)))
    two = "\n".join(status_lines(_snap(2)))
    assert "1 contact," in one + "," and "1 contacts" not in one
    assert "2 contacts" in two
    knob = status_lines({"demo": "knob", "knob": {"crossings": 1, "condition": "c", "item": 1}})
    assert "1 crossing" in knob[-1] and "1 crossings" not in knob[-1]


def test_the_finger_position_is_shown_once(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 30, "scenes")
            demos, targets = app.session.demos, []
            # a running demo whose twin camera the operator can touch (no demo process)
            demos.touchable = lambda: object()
            demos.set_target = lambda pos: targets.append(pos) or True
            app.session.emit(Started("demo", "flow"))
            pane = app.pane("scenes")
            await wait_for(pilot, lambda: pane.demo_state == "running", 30, "running")
            demos.last_snapshot = _snap(1)
            app.session.emit(Snapshot("demo", "flow", data=_snap(1)))
            await wait_for(pilot, lambda: "1 contact" in _screen(app), 30, "the snapshot")
            assert "1 contacts" not in _screen(app)
            assert "space puts your finger" in _screen(app)
            for keys in (("space",), ("right",)):
                await pilot.press(*keys)
                await wait_for(pilot, lambda: pane.hand_placed, 10, "finger placed")
                x, y = pane.hand_mm
                # the camera sees the hand's middle, not the fingertip: elsewhere
                app.session.emit(Snapshot("demo", "flow", data=_snap(1, (x + 9, y - 55))))
                where = f"at {x:.0f},{y:.0f} mm"
                await wait_for(pilot, lambda w=where: w in _screen(app), 30, where)
                await pilot.pause()
                shown = _screen(app)
                assert len(re.findall(re.escape(where), shown)) == 1, shown
                assert "arrows move" in shown and "space lifts" in shown
            await wait_for(pilot, lambda: targets and targets[-1] == pane.hand_mm, 10, "sent")

    asyncio.run(scenario())
