"""The Devices screen (issue 27, third new-user try): l says on the status line that it
listed the sound cards and relay boards again and what it found; enter on a relay board
whose probe reports ``error`` says in one line why and what to do, touching nothing."""

from __future__ import annotations

import asyncio

from textual.widgets import DataTable

from console.cli.main import Context
from console.config.profile import overrides_path
from console.core.types import DeviceStatus
from console.tui.app import HapTableApp
from console.tui.panes import devices

from .conftest import wait_for, words_on


def _hid_broken(real):
    def boards(profile, plugins, held=None):
        rows = real(profile, plugins, held)
        why = "permission denied; add a udev rule"  # as drivers word it: the fix at the end
        bad = DeviceStatus("relay_board", "hid", "error", why, "add a udev rule")
        return [(n, d, bad) if n == "hid" else (n, d, s) for n, d, s in rows]

    return boards


def _app(plugins) -> HapTableApp:
    return HapTableApp(Context("sim", plugins), fast=True, initial="devices")


def test_l_says_it_listed_the_devices_again(plugins):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            table = app.query_one("#relay-table", DataTable)
            await wait_for(pilot, lambda: table.row_count > 0, 30, "relay boards listed")
            assert "listed" not in words_on(app, "#devices-result")
            await pilot.press("l")
            await wait_for(
                pilot, lambda: "listed again" in words_on(app, "#devices-result"), 30, "said"
            )
            said = words_on(app, "#devices-result")
            assert "relay board" in said and "sound card" in said, said

    asyncio.run(scenario())


def test_enter_on_a_relay_board_in_error_says_why_and_touches_nothing(plugins, monkeypatch):
    monkeypatch.setattr(devices, "relay_boards", _hid_broken(devices.relay_boards))

    async def scenario():
        app = _app(plugins)
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
            await wait_for(pilot, lambda: "hid" in words_on(app, "#devices-result"), 30, "said")
            await pilot.pause(0.5)  # a pick would be saving and reopening by now
            said = words_on(app, "#devices-result")
            assert "error" in said and "udev rule" in said and "press l" in said, said
            assert said.count("udev rule") == 1 and "is error" not in said, said
            assert not overrides_path("sim").exists()
            assert app.session.outputs is outputs  # not reopened

    asyncio.run(scenario())
