"""A running demo's status on Scenes (F6) shows the camera's rate and the loop's apart,
with the drop counts, at 80 columns as at 120 (README: "the status shows the camera's
rate and the loop's apart"); the knob's own line and the demos' keys stay in view."""

from __future__ import annotations

import asyncio
import re

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from plugins.demos.panel import fit_fields
from plugins.demos.status import status_lines

from .conftest import wait_for
from .test_camera_layout import SIZES, screen_lines
from .test_demos import _start

RATES = re.compile(r"camera set to \d+ fps, loop \d+ fps, dropped \d+ \(camera\) \+ \d+ \(queue\)")

#: a running flow's snapshot as its process reports it (every line it has)
FLOW = {
    "demo": "flow",
    "running": True,
    "uptime_s": 12.0,
    "watchdog": {"limit_ms": 250.0},
    "camera": {"rate_fps": 60.0, "fps": 48.0},
    "latency": {"fps": 47.0, "dropped_camera": 266, "dropped_queue": 0},
    "hand": {"hands": 1, "rest_mm": (543.0, 181.0), "contacts": 0, "gesture": "static_hand"},
    "flow": {"direction": "right", "flows": 3, "last": []},
}


@pytest.mark.parametrize("width", [78, 118])
def test_the_rates_and_drops_fit_the_status_width(width):
    text = fit_fields("\n".join(status_lines(FLOW)), width).plain
    assert RATES.search(text), text
    assert "watchdog ok (250 ms)" in text and "flow running 12 s" in text, text
    assert all(len(line) <= width for line in text.split("\n")), text


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_a_running_knob_shows_both_rates(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=size) as pilot:
            pane = await _start(app, pilot, "knob")
            shown = lambda: "\n".join(screen_lines(app))  # noqa: E731
            await wait_for(pilot, lambda: RATES.search(shown()), 30, "both rates")
            await wait_for(pilot, lambda: "crossing" in shown(), 30, "the knob's line")
            assert "demos (d): enter start/stop" in shown()
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.demo_name is None, 30, "demo stopped")

    asyncio.run(scenario())
