"""Devices (F1) shows the same checks as `haptable doctor`, at 80 x 24 and 120 x 40:
its device rows are the doctor's own list, so a check added to doctor shows on F1 (the
classifier's touch-calibration row, ``gestures svm``, was missing there: a new
operator's try)."""

from __future__ import annotations

import asyncio
import json

import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines
from .test_devices_selftest_what_ran import _haptable


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_devices_rows_are_the_doctors_checks(plugins, size):
    doctor = _haptable("doctor", "--json")
    checks = [(d["kind"], d["name"]) for d in json.loads(doctor.stdout)["devices"]]
    assert ("gestures", "svm") in checks, checks

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            table = app.query_one("#device-table", DataTable)
            pane = app.pane("devices")
            await wait_for(pilot, lambda: table.row_count >= 7, 30, "the devices checked")
            await pilot.pause(0.2)
            rows = [(s.kind, s.name) for s in pane.doctor_rows if s.kind != "selftest"]
            assert rows == checks, rows
            table.focus()  # every row whole: each check's row on the screen
            await pilot.pause(0.3)
            shown = "\n".join(screen_lines(app))
            assert any("gestures" in ln and "svm" in ln for ln in shown.split("\n")), shown

    asyncio.run(scenario())
