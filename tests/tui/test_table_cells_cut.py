"""A table's cell its column cuts ends in ``…`` (Devices' plugins table showed
``sound card through Port`` with nothing saying words went), and Enter on a row of
either Devices table is named the same way in the footer."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.focus_keys import shown_words

from .conftest import wait_for


def test_a_cut_cell_says_so_and_both_tables_name_enter_alike(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            table = app.query_one("#plugin-table")
            await wait_for(pilot, lambda: table.row_count >= 3, 20, "the plugins listed")
            await pilot.pause(0.3)
            rows = [table.render_line(i).text for i in range(1, 4)]
            cut = [r for r in rows if "sound card through" in r or "simulated" in r]
            assert cut and all(r.rstrip().endswith("…") for r in cut), rows
            device = app.query_one("#device-table")
            assert shown_words(table)["enter"] == shown_words(device)["enter"] == "whole row"

    asyncio.run(scenario())
