"""The Latency screen says how many frames each row counts: the end-to-end row counts
only the frames that scheduled output, so its p99 can be below the vision row's (a new
user read that as a wrong sum)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def _stage(n: int, p99: float) -> dict:
    return {"n": n, "p50_ms": p99 / 2, "p99_ms": p99, "max_ms": p99 + 1}


def test_each_row_says_the_frames_it_counts(plugins):
    snap = {
        "stages": {"vision": _stage(600, 9.0), "scheduled": _stage(37, 0.4)},
        "end_to_end": _stage(37, 5.0),
        "capture_to_arrival": _stage(600, 1.0),
    }

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("latency") is not None, 30, "latency")
            pane, table = app.pane("latency"), app.query_one("#lat-table")
            pane._show_rows(table, snap, None)
            await pilot.pause(0.2)
            heads = [str(c.label) for c in table.columns.values()]
            assert heads[:5] == ["stage", "p50 ms", "p99 ms", "max ms", "frames"], heads
            rows = {
                str(r[0]): [str(c) for c in r]
                for r in map(table.get_row_at, range(table.row_count))
            }
            assert rows["vision"][2:5] == ["9.00", "10.00", "600"], rows
            assert rows["end to end"][2:5] == ["5.00", "6.00", "37"], rows
            assert rows["output"][4] == "37", rows
            help_text = " ".join(type(pane).HELP_TEXT.split())
            assert "end to end's p99 can be below another row's" in help_text

    asyncio.run(scenario())
