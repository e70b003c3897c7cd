"""Issue 27 (Studies): a resize re-lays the form's first row (protocol, participant, the
checkboxes), the folder row and the buttons: from 120 to 80 columns every control is
inside the screen, and back at 120 the dropdown shows the longest protocol name again."""

from __future__ import annotations

import asyncio

from textual.widgets import Select

from console.cli.main import Context
from console.tui.app import HapTableApp
from plugins.studies import protocol as protocols

from ..studies.studies_pilot import studies_idle
from .conftest import wait_for

ROWS = ("#study-form", "#study-folder", "#study-buttons")


def _outside(app, width: int) -> list[str]:
    """The controls of the top rows that reach past ``width`` columns."""
    return [
        f"{row} {type(w).__name__}#{w.id} ends at {w.region.right}"
        for row in ROWS
        for w in app.query_one(row).children
        if w.display and (w.region.width == 0 or w.region.right > width)
    ]


def test_a_resize_re_lays_the_top_rows(plugins):
    longest = max(len(n) for n in protocols.available())

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=(120, 40)) as pilot:
            await studies_idle(app, pilot)
            select = app.query_one("#protocol", Select)
            assert select.region.width >= longest and not _outside(app, 120)
            await pilot.resize_terminal(80, 24)
            await wait_for(pilot, lambda: app.size.width == 80, 10, "80 columns")
            await pilot.pause()
            assert not _outside(app, 80), _outside(app, 80)
            await pilot.resize_terminal(120, 40)
            await wait_for(pilot, lambda: select.region.width >= longest, 10, "wide again")
            assert not _outside(app, 120)

    asyncio.run(scenario())
