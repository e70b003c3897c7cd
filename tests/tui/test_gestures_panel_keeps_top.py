"""A second new operator's try: the Gestures panel (Camera `g`) covered the title row and
the tab bar. It opens over the Camera screen below them: the console's title and every
screen's tab stay in view, the panel's own title under them."""

from __future__ import annotations

import asyncio
import re

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera import _first_frame


def _shown(app) -> list[str]:
    """The terminal's rows as the operator sees them: the screens below a modal one
    shown through it (what ``render_strips`` alone leaves out)."""
    svg = app.export_screenshot()
    rows = re.findall(r'<text class="[^"]*" x="[^"]*" y="([^"]*)"[^>]*>([^<]*)</text>', svg)
    by_y: dict[float, str] = {}
    for y, text in rows:
        by_y[float(y)] = by_y.get(float(y), "") + text.replace("&#160;", " ")
    return [by_y[y] for y in sorted(by_y)]


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_gestures_panel_leaves_the_title_row_and_tab_bar(plugins, size):
    from plugins.gestures.panel import GesturesPanel  # lazy: the plugin under test

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("g")
            await wait_for(pilot, lambda: isinstance(app.screen, GesturesPanel), 10, "panel")
            await pilot.pause(0.3)
            rows = _shown(app)
            top = "\n".join(rows[:4])
            assert "HapTable" in rows[0], top
            assert "Devices" in rows[1] and "Camera" in rows[1] and "Studies" in rows[1], top
            assert any("Gestures: twin datasets" in r for r in rows[3:6]), "\n".join(rows[:8])

    asyncio.run(scenario())
