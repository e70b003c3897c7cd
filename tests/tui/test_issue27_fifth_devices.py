"""Devices at 80 x 24 (issue 27, fifth new-user try): a refusal on a row (a relay
board that is missing) is in the log too; the e-stop's refusal of the test signal is
replaced by the reset; every cut cell ends in "…" (no cell runs off the screen)."""

from __future__ import annotations

import asyncio
import logging

from textual.widgets import DataTable

from console.runtime.context import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def _row_of(table: DataTable, text: str) -> int | None:
    for i in range(table.row_count):
        if any(text == str(c) for c in table.get_row_at(i)):
            return i
    return None


def _cells_fit(table: DataTable, width: int) -> list[str]:
    """The cells that run past ``width`` columns without ending in "…"."""
    cols = list(table.columns.values())
    bad = []
    for i in range(table.row_count):
        x = 0
        for col, cell in zip(cols, table.get_row_at(i), strict=True):
            x += col.get_render_width(table)
            if x > width and not str(cell).endswith("…") and str(cell).strip():
                bad.append(str(cell))
    return bad


def test_devices_refusals_logged_reset_said_cells_fit(plugins, caplog):
    caplog.set_level(logging.INFO)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            relays = app.query_one("#relay-table", DataTable)
            await wait_for(pilot, lambda: _row_of(relays, "hid") is not None, 30, "listed")
            devices = app.query_one("#device-table", DataTable)
            await wait_for(pilot, lambda: devices.row_count > 0, 30, "doctor")
            for table in (relays, devices):
                assert _cells_fit(table, 80 - 2) == [], table.id
            # a missing board's refusal: on the status line and in the log
            relays.focus()
            relays.move_cursor(row=_row_of(relays, "hid"))
            await pilot.press("enter")
            pane = app.pane("devices")
            await wait_for(
                pilot, lambda: "relay board 'hid' cannot be opened" in pane.result, 30, "said"
            )
            logged = [r.getMessage() for r in caplog.records]
            assert any("relay board 'hid' cannot be opened" in m for m in logged), logged[-5:]
            # the e-stop refuses the test signal; the reset replaces the refusal
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 30, "e-stopped")
            await pilot.press("t")
            await wait_for(pilot, lambda: "refused" in pane.result, 30, "refused")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: pane.result.startswith("e-stop reset"), 30, "reset")
            assert "ctrl+r resets" not in str(app.query_one("#devices-result").content)

    asyncio.run(scenario())


def test_long_work_names_its_panel_in_the_log():
    """A long job's line is logged under its panel's name (``Gestures: ...``), not the
    job's (``status synthesizing 5 x 10 x 40: ...``)."""
    from console.tui.said import screen_name

    class GesturesPanel:
        pass

    class Work:
        ancestors_with_self = [object(), GesturesPanel()]

    assert screen_name(Work(), "synthesizing 5 x 10 x 40") == "Gestures"
