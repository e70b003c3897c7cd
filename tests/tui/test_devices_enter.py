"""The Devices screen (issue 27): enter on a relay board the probe finds missing says in
one line why it cannot be used and what to do, touching nothing (no file saved, the
outputs and their switch log stay); d says it re-checked; the plugins table ends a cut
text in "…" and fits 80 columns."""

from __future__ import annotations

import asyncio

from textual.widgets import DataTable, Static

from console.cli.main import Context
from console.config.profile import overrides_path
from console.core.types import DeviceStatus
from console.tui.app import HapTableApp
from console.tui.panes import devices

from .conftest import wait_for


def _result(app) -> str:
    return " ".join(str(app.query_one("#devices-result", Static).render()).split())


def _hid_missing(real):
    def boards(profile, plugins, held=None):
        rows = real(profile, plugins, held)
        return [
            (n, d, DeviceStatus("relay_board", n, "missing", "no board", "plug it in"))
            if n == "hid"
            else (n, d, s)
            for n, d, s in rows
        ]

    return boards


def test_enter_on_a_missing_relay_board_says_why_and_touches_nothing(plugins, monkeypatch):
    monkeypatch.setattr(devices, "relay_boards", _hid_missing(devices.relay_boards))

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            outputs = app.session.outputs
            table = app.query_one("#relay-table", DataTable)
            await wait_for(pilot, lambda: table.row_count > 0, 30, "relay boards listed")
            hid = next(i for i in range(table.row_count) if "hid" in str(table.get_row_at(i)[1]))
            table.focus()
            table.move_cursor(row=hid)
            await pilot.pause(0.2)
            await pilot.press("enter")
            await wait_for(pilot, lambda: "hid" in _result(app), 30, "said")
            await pilot.pause(0.5)  # a pick would be saving and reopening by now
            said = _result(app)
            assert "missing" in said and "plug it in" in said and "press l" in said, said
            assert "saving" not in said and "overrides" not in said, said
            assert not overrides_path("sim").exists()
            assert app.session.outputs is outputs  # not reopened: its switch log stays

    asyncio.run(scenario())


def test_d_says_it_re_checked_the_devices(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            table = app.query_one("#device-table", DataTable)
            await wait_for(pilot, lambda: table.row_count > 0, 30, "doctor rows")
            assert _result(app) == ""
            await pilot.press("d")
            await wait_for(pilot, lambda: "re-checked" in _result(app), 30, "said")
            assert "simulated" in _result(app), _result(app)

    asyncio.run(scenario())


def test_the_plugins_table_ends_a_cut_text_in_an_ellipsis_and_fits(plugins):
    long = max(
        (r.description for regs in plugins.registrations.values() for r in regs.values()),
        key=len,
    )

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            table = app.query_one("#plugin-table", DataTable)
            await wait_for(pilot, lambda: table.row_count > 0, 30, "plugins listed")
            cells = [str(c) for i in range(table.row_count) for c in table.get_row_at(i)]
            assert long not in cells and any(c.endswith("…") for c in cells), cells
            width = sum(c.get_render_width(table) for c in table.columns.values())
            assert width <= app.pane("devices").scrollable_content_region.width, width

    asyncio.run(scenario())
