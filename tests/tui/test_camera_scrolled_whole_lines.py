"""A new operator's try (issue 27, newuser7 #7): Camera (F2) at 80 x 24 with the twin's
hand in view showed ``   last 3 s`` alone under ``(104% of contact_level 180)``: the
side panel's scrolled part, scrolled just enough to keep the chosen setting (``▸``) in
view, began inside a wrapped line (``both rates: frames in the same`` / ``last 3 s``).
The scrolled part starts with a whole line: the line's head, or the next line."""

from __future__ import annotations

import asyncio
import time

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.camera_live import HANG
from console.tui.camera_side import whole_top

from .conftest import wait_for
from .test_camera_layout import _first_frame, text_in

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


def test_a_scroll_inside_a_wrapped_line_moves_to_a_whole_one():
    lines = ["both rates: frames in the same", f"{HANG}last 3 s", "view: camera", "x"]
    assert whole_top(lines, 1, keep=4, height=5) == 0  # its head, the ▸ row kept in view
    assert whole_top(lines, 1, keep=5, height=5) == 2  # else the line goes whole
    assert whole_top(lines, 2, keep=5, height=5) == 2
    assert whole_top(lines, 0, keep=3, height=5) == 0


@SIZES
def test_the_side_panel_never_starts_inside_a_wrapped_line(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            info = app.query_one("#camera-info")
            await wait_for(pilot, lambda: "hands 1" in text_in(app, info), 30, "the hand")
            scroll, detail = app.query_one("#camera-scroll"), app.query_one("#camera-detail")
            cut, tops = [], set()
            t_end = time.monotonic() + 6.0
            while time.monotonic() < t_end:
                await pilot.pause(0.05)
                lines = str(detail.content).split("\n")
                top = int(scroll.scroll_y) - detail.virtual_region.y
                tops.add(top)
                if 0 < top < len(lines) and lines[top].startswith(HANG):
                    cut.append((top, lines[top - 1], lines[top]))
            assert not cut, cut[:3]
            assert "▸" in text_in(app, app.query_one("#camera-settings")), tops

    asyncio.run(scenario())
