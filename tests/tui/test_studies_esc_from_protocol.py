"""Studies (F10) at 80 x 24 and 120 x 40: Esc on the closed protocol drop-down gives
the focus to Start, as Esc in a text field does (it stayed on the drop-down)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Select

from console.cli.main import Context
from console.tui.app import HapTableApp

from ..studies.studies_pilot import studies_idle
from .conftest import wait_for
from .test_camera_layout import SIZES


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_esc_on_the_protocol_drop_down_focuses_start(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            pane = await studies_idle(app, pilot)
            select = pane.query_one("#protocol", Select)
            select.focus()
            await wait_for(pilot, lambda: select.has_focus, 5, "the drop-down")
            await pilot.press("escape")
            await pilot.pause(0.2)
            assert app.focused is pane.query_one("#start"), app.focused

    asyncio.run(scenario())
