"""Devices (F1): the self-test's row says what ran, as `haptable doctor` said it: its
quick part's outcome (ok, error, skipped) with where and when, and that the full one was
not run from the console; never `full not run` alone after a doctor's `quick ok` (a new
operator's try). A full one run here (s) is kept for the row after a restart."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys

import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.runtime.selftest_last import note_last, read_last
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines


def _haptable(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "console.cli.main", "--profile", "sim", *args],
        capture_output=True,
        text=True,
        timeout=300,
        env=os.environ.copy(),
    )


def _selftest_row(app) -> str:
    pane = app.pane("devices")
    row = next((s for s in pane.doctor_rows if s.kind == "selftest"), None)
    return "" if row is None else f"{row.name} {row.state} {row.why} | {row.fix}"


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_selftest_row_says_the_doctors_quick_part(plugins, size):
    saved = _haptable("selftest", "--save-baseline", "--fast")  # a healthy table's baseline
    assert saved.returncode == 0, saved.stderr
    doctor = _haptable("doctor")
    assert "selftest   quick        ok" in doctor.stdout, doctor.stdout

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            table = app.query_one("#device-table", DataTable)
            await wait_for(pilot, lambda: table.row_count >= 7, 30, "the devices checked")
            row = _selftest_row(app)
            # its outcome first (what a shortened row keeps), who and when after it
            assert row.startswith("quick ok quick self-test ok ("), row
            assert "); haptable doctor at " in row, row
            assert "all paths healthy" in row, row
            assert "the full one not run from the console" in row, row
            # on the painted screen (a frame after the table's rows were added)
            shown = lambda: any("selftest" in ln and "quick" in ln for ln in screen_lines(app))  # noqa: E731
            await wait_for(pilot, shown, 10, "the self-test row on screen")

    asyncio.run(scenario())


def test_a_full_run_kept_says_itself_and_the_doctors_skip_says_why(plugins):
    doctor = _haptable("doctor")  # no baseline yet: its quick part skipped, said why
    assert "selftest   quick        skipped" in doctor.stdout, doctor.stdout
    assert read_last("sim")["quick"]["state"] == "skipped"
    from console.tui.selftest_action import selftest_row

    row = selftest_row(None, read_last("sim"))
    assert (row.name, row.state) == ("quick", "skipped")
    assert "no baseline yet" in row.why and "the full one not run" in row.why, row.why
    note_last("sim", "full", "ok", "self-test: all paths healthy (3 s)", "the console's s")
    row = selftest_row(None, read_last("sim"))
    assert (row.name, row.state) == ("full", "ok"), row
    assert row.why.startswith("all paths healthy (3 s) (the console's s, "), row.why
