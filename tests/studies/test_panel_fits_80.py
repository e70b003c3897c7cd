"""The Studies screen at 80 x 24 (issue 27): every column of the trials table shows whole,
the ``time`` column too (the trial's description gives way, ending in ``…``)."""

from __future__ import annotations

import asyncio

from textual.widgets import DataTable

from .studies_pilot import wait_for
from .test_panel_issue27 import _app, _running


def _screen_lines(app) -> list[str]:
    return [strip.text for strip in app.screen._compositor.render_strips()]


def test_the_trials_table_shows_every_column_at_80_columns(double_plugins, map_file, tmp_path):
    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _running(pilot, app, map_file, tmp_path)
            pane.control.abort("stopped by the test")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            table = pane.query_one("#study-trials", DataTable)
            long = {  # a trial with a long description (exp1's pairs read so)
                "trial": 98,
                "phase": "familiarisation",
                "pair": "F",
                "direction": "left_to_right and back again, twice over",
                "response": "left_to_right",
                "correct": True,
                "replays": 0,
                "response_time_s": 1.23,
            }
            pane._add_row(long)
            await pilot.pause(0.3)
            assert table.row_count >= 2
            lines = _screen_lines(app)
            header = [x for x in lines if "trial" in x and "what" in x]
            assert header and "time" in header[0], "\n".join(lines)
            # the newest row (the cursor's, in view) shows its time whole, its long
            # description cut to what is left ("…")
            row = [str(c) for c in table.get_row_at(table.row_count - 1)]
            assert row[0] == "99" and row[1].endswith("…") and row[-1] == "1.23 s", row
            assert any(x.split()[:1] == ["99"] and "1.23 s" in x for x in lines), "\n".join(lines)
            width = sum(c.get_render_width(table) for c in table.columns.values())
            assert width <= table.scrollable_content_region.width, width

    asyncio.run(scenario())
