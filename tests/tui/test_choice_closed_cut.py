"""A closed drop-down narrower than its chosen name ends the name with ``…`` at 80 x 24
and 120 x 40: Studies' (F10) protocol drop-down showed ``threshold_vib ▼`` at 80 x 24,
a name cut mid-word with nothing saying so."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Select

from console.cli.main import Context
from console.tui.app import HapTableApp

from ..studies.studies_pilot import studies_idle
from .test_camera_layout import SIZES, screen_lines


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_closed_protocol_drop_down_is_whole_or_ends_in_an_ellipsis(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            pane = await studies_idle(app, pilot)
            select = pane.query_one("#protocol", Select)
            select.value = "threshold_vibrotactile"
            await pilot.pause(0.3)
            r = select.region
            shown = screen_lines(app)[r.y][r.x : r.right].replace("▼", "").strip()
            name = "threshold_vibrotactile"
            assert shown == name or (shown.endswith("…") and name.startswith(shown[:-1])), shown

    asyncio.run(scenario())
