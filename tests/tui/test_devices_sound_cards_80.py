"""Issue 27, fourth new-user try: the Devices screen's sound-card table fits 80 columns,
its last column (note) included: the default card's "default" and a card's note show on
its row, not cut off the screen after the latency."""

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


def test_the_sound_card_table_shows_every_column_at_80(plugins):
    plugins = load_plugins(extra={"bench_card": _bench_card_plugin()})

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            table = app.query_one("#audio-table", DataTable)
            await wait_for(pilot, lambda: table.row_count >= 4, 30, "sound cards listed")
            table.focus()
            # a generous bound on a wait (the clean-clone CI, loaded, drew the rows after 10 s)
            await wait_for(pilot, lambda: "Bench mic" in _line_with(app, "Bench mic"), 30)
            # the header as drawn with the rows (a listing arriving later lays the table
            # out again: a loaded machine read it between the two)
            await wait_for(
                pilot,
                lambda: _line_with(app, "driver       device").rstrip().endswith("note"),
                30,
                "the header with the rows",
            )
            header = _line_with(app, "driver       device")
            assert header.rstrip().endswith("note"), header
            assert "low/high ms" in header, header
            # the note takes what the other columns leave (cut after a whole word with …,
            # a first word too wide where it must: a scroll bar may take two columns), on
            # the card's row
            # the card's note "1 output": whole, or "1…" where a scroll bar takes its room
            mic = _line_with(app, "Bench mic")
            assert mic.rstrip().endswith(("1 output", "1…")), mic
            assert "defa" in _line_with(app, "Bench Card A"), _line_with(app, "Card A")

    asyncio.run(scenario())
