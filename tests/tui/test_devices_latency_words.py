"""The Devices screen (F1) at 80 x 24: a sound card's latency column says which number
is the low and which the high latency (not a bare "1.3-4.0", which reads as a range)."""

from __future__ import annotations

import asyncio

from textual.widgets import DataTable

from console.config.plugins import load_plugins
from console.runtime.context import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines
from .test_devices import _bench_card_plugin


def _line_with(app, text: str) -> str:
    return next((line for line in screen_lines(app) if text in line), "")


def test_the_latency_column_says_low_and_high():
    plugins = load_plugins(extra={"bench_card": _bench_card_plugin()})

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            table = app.query_one("#audio-table", DataTable)
            await wait_for(pilot, lambda: table.row_count >= 4, 30, "sound cards listed")
            table.focus()
            await wait_for(
                pilot, lambda: "Bench Card A" in _line_with(app, "Bench Card A"), 30, "the rows"
            )
            # the header as drawn with the rows (a listing arriving later lays the table
            # out again: a loaded machine read it between the two)
            await wait_for(
                pilot,
                lambda: _line_with(app, " ch ").rstrip().endswith("note"),
                30,
                "the header with the rows",
            )
            header = _line_with(app, " ch ")
            assert "low/high ms" in header, "\n".join(screen_lines(app))
            cells = [str(table.get_row_at(i)[5]) for i in range(table.row_count)]
            shown = [c for c in cells if c not in ("", "-")]
            assert shown, cells
            for c in shown:  # low first, then high, never a range's dash
                low, high = c.split("/")
                assert float(low) <= float(high), c
            assert header.rstrip().endswith("note"), header  # still fits 80 columns
            assert "low/high ms: its latency" in _line_with(app, "sound card (")

    asyncio.run(scenario())
