"""An open menu never covers the safety bar (the e-stop state) or the footer: Devices'
test-signal list at 80 x 24 was pushed up over both (new operator's report, finding 15);
it now ends above the bar and scrolls within itself (``console.tui.menus.menu_above``)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import DataTable, Select
from textual.widgets._select import SelectOverlay

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.safety_bar import SafetyBar

from .conftest import wait_for


def _rows(app) -> list[str]:
    return [s.text for s in app.screen._compositor.render_strips()]


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_test_signal_menu_ends_above_the_safety_bar(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            select = app.query_one("#stimulus", Select)
            table = app.query_one("#plugin-table", DataTable)  # the screen filled in
            await wait_for(pilot, lambda: table.row_count > 0, 20, "the plugin table")
            select.focus()
            await pilot.press("enter")
            await wait_for(pilot, lambda: isinstance(app.focused, SelectOverlay), 10, "open")
            menu = app.focused
            await pilot.pause(0.3)
            bar = app.query_one(SafetyBar)
            assert menu.region.height >= 5, menu.region  # its border and 3 options at least
            assert menu.region.bottom <= bar.region.y, (menu.region, bar.region)
            rows = _rows(app)
            assert "E-STOP" in rows[bar.region.y], rows[bar.region.y]  # the bar drawn whole
            assert "f1-f10 screens" in rows[-1], rows[-1]  # and the footer
            await pilot.press("down", "down", "enter")  # the menu still works
            await wait_for(pilot, lambda: select.value == "sine-PC", 10, "a pick")

    asyncio.run(scenario())
