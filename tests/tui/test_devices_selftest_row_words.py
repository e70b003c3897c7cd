"""Devices (F1): the self-test's row says what `haptable doctor` says, in its words.
On a table with no baseline and no doctor run yet, the row said `full not run` while
`haptable doctor` said its quick part `skipped: no baseline yet`; after a restart, a run
the e-stop stopped read `(by the e-stop at 23:32:34, 2026-11-30 23:32)`: its time said
twice (a new operator's try)."""

from __future__ import annotations

import asyncio
import re

import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.runtime.selftest_last import note_last, read_last
from console.tui.app import HapTableApp
from console.tui.selftest_stopped import kept_stopped, stopped_when

from .conftest import wait_for
from .test_camera_layout import screen_lines
from .test_devices_selftest_what_ran import _haptable


def _row(app):
    return next(s for s in app.pane("devices").doctor_rows if s.kind == "selftest")


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_row_says_the_doctors_skip_before_any_doctor_ran(plugins, size):
    assert read_last("sim") == {}  # no doctor, no run: nothing kept

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            table = app.query_one("#device-table", DataTable)
            await wait_for(pilot, lambda: table.row_count >= 7, 30, "the devices checked")
            row = _row(app)
            assert (row.name, row.state) == ("quick", "skipped"), row
            assert row.why.startswith("quick self-test skipped (no baseline yet: press s on a"), row
            assert "haptable selftest" not in row.why, row.why  # the console's key
            assert row.fix == "press s (full)", row
            shown = lambda: any("selftest" in ln and "skipped" in ln for ln in screen_lines(app))  # noqa: E731
            await wait_for(pilot, shown, 10, "the row on screen")

    asyncio.run(scenario())
    doctor = _haptable("doctor")  # the same word and reason at a shell
    assert "selftest   quick        skipped   skipped: no baseline yet" in doctor.stdout


def test_a_stopped_run_kept_says_its_time_once_after_a_restart(plugins):
    # as a console kept it before (its time of day in the line too), and as it keeps it now
    for line in ("by the e-stop at 23:32:34", "by the e-stop"):
        note_last("sim", "stopped", "stopped", line, "the console's s")
        when = read_last("sim")["stopped"]["time"]

        async def scenario(when: str = when):
            app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
            async with app.run_test(size=(120, 40)) as pilot:
                table = app.query_one("#device-table", DataTable)
                await wait_for(pilot, lambda: table.row_count >= 7, 30, "the devices checked")
                row = _row(app)
                assert row.state == "stopped", row
                said = f"the last run stopped before its end (by the e-stop at {when})"
                assert row.why.startswith(said), row.why
                assert len(re.findall(r"\d\d:\d\d", row.why)) == 1, row.why

        asyncio.run(scenario())


def test_a_stopped_run_is_said_what_then_when():
    assert stopped_when("by the e-stop", "23:32:34") == "by the e-stop at 23:32:34"
    assert stopped_when("PC: no signal", "23:32:34") == "at 23:32:34: PC: no signal"
    old = {"line": "at 23:32:34: PC: no signal", "time": "2026-11-30 23:32"}
    assert kept_stopped(old) == "at 2026-11-30 23:32: PC: no signal"
