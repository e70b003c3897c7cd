"""A status line says what is true now (a new operator's try, finding 11): a line about a
state goes or changes when that state changes (``console.tui.lapse.lapse_on_change``).

- Camera: ``vision settings kept in ...`` stayed after ``h`` changed a setting, which was
  then unsaved;
- Gestures (Camera ``g``): ``subjects 'abc': give a whole number ...`` stayed after the
  field was corrected;
- Devices: a relay board's ``cannot be opened`` line stayed for minutes after the
  operator moved on;
- Devices: the self-test row kept ``ok all paths healthy`` after a run the e-stop
  stopped.
"""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.runtime.selftest_last import read_last
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import SIZES, _first_frame

IDS = ["80x24", "120x40"]


def _camera_status(app) -> str:
    return " ".join(str(app.query_one("#camera-status").render()).split())


@pytest.mark.parametrize("size", SIZES, ids=IDS)
def test_camera_kept_settings_line_changes_when_a_setting_changes(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("W", "W")
            await wait_for(pilot, lambda: "settings kept in" in _camera_status(app), 10, "kept")
            await pilot.press("h")
            await wait_for(
                pilot, lambda: "changed since kept in" in _camera_status(app), 5, "changed"
            )
            assert "W keeps these" in _camera_status(app)

    asyncio.run(scenario())


def _work_line(panel) -> str:
    return " ".join(panel.work.text.split())


@pytest.mark.parametrize("size", SIZES, ids=IDS)
def test_gestures_field_refusal_goes_once_the_field_reads(plugins, size):
    from textual.widgets import Input

    from .test_gestures_panel_80 import _panel

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            panel = await _panel(app, pilot, plugins)
            subjects = panel.query_one("#gp-subjects", Input)
            subjects.value = "abc"
            await pilot.press("s")
            await wait_for(pilot, lambda: "subjects 'abc'" in _work_line(panel), 5, "refused")
            subjects.value = "abd"  # still wrong: the line names what is typed now
            await wait_for(pilot, lambda: "subjects 'abd'" in _work_line(panel), 5, "again")
            subjects.value = "2"  # corrected: the refusal goes, the keys are offered
            await wait_for(pilot, lambda: "subjects" not in _work_line(panel), 5, "gone")
            assert _work_line(panel).startswith("s: synthesize"), _work_line(panel)
            panel.query_one("#gp-cv", Input).value = "3fold"
            await pilot.press("t")
            await wait_for(pilot, lambda: "cv '3fold'" in _work_line(panel), 5, "cv refused")
            panel.query_one("#gp-cv", Input).value = "loso"
            await wait_for(pilot, lambda: "cv" not in _work_line(panel), 5, "cv gone")

    asyncio.run(scenario())


def _row_of(table, text: str) -> int | None:
    for i in range(table.row_count):
        if any(text == str(c) for c in table.get_row_at(i)):
            return i
    return None


@pytest.mark.parametrize("size", SIZES, ids=IDS)
def test_devices_board_line_goes_when_the_operator_moves_on(plugins, size):
    from textual.widgets import DataTable

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            relays = app.query_one("#relay-table", DataTable)
            await wait_for(pilot, lambda: _row_of(relays, "hid") is not None, 30, "listed")
            pane = app.pane("devices")
            said = "relay board 'hid' cannot be opened"
            relays.focus()
            relays.move_cursor(row=_row_of(relays, "hid"))
            await pilot.press("enter")
            await wait_for(pilot, lambda: said in pane.result, 30, "said")
            await pilot.pause(1.2)  # on its row: it stays
            assert said in pane.result
            await pilot.press("down")  # the cursor leaves the board's row: the line goes
            await wait_for(pilot, lambda: pane.result == "", 5, "gone with the row")
            assert not app.query_one("#devices-result").display
            relays.move_cursor(row=_row_of(relays, "hid"))
            await pilot.press("enter")
            await wait_for(pilot, lambda: said in pane.result, 30, "said again")
            await pilot.press("f2")  # another screen: the operator moved on
            await wait_for(pilot, lambda: pane.result == "", 5, "gone with the screen")

    asyncio.run(scenario())


def _selftest_row(app) -> str:
    row = next((s for s in app.pane("devices").doctor_rows if s.kind == "selftest"), None)
    return "" if row is None else f"{row.state} {row.why} | {row.fix}"


@pytest.mark.parametrize("size", SIZES, ids=IDS)
def test_devices_selftest_row_says_a_run_the_estop_stopped(plugins, size):
    async def scenario():
        # the paced table the console shares with the self-test (as
        # test_devices_selftest_refused)
        app = HapTableApp(Context("sim", plugins), fast=False, initial="devices")
        async with app.run_test(size=size) as pilot:
            pane = app.pane("devices")
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: bool(pane.doctor_rows), 30, "doctor rows")
            # a healthy run here before (its outcome as the console keeps it)
            pane.selftest_done = (True, "self-test: all paths healthy (12 s)", 12.0)
            pane._show(pane.doctor_rows[:-1])
            assert _selftest_row(app).startswith("ok all paths healthy"), _selftest_row(app)
            await pilot.press("s")
            await wait_for(pilot, lambda: "s again" in pane.result, 10, "asked")
            await pilot.press("s")
            await wait_for(pilot, lambda: "self-test:" in pane.result, 20, "running")
            await pilot.pause(1.0)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: "self-test stopped" in pane.result, 60, "stopped")
            row = _selftest_row(app)
            assert row.startswith("stopped the last run stopped before its end (by the e-stop"), row
            assert "the last whole one: ok all paths healthy" in row, row
            assert row.endswith("| s runs it again (ctrl+r first)"), row
            # reset: the row's fix no longer asks for ctrl+r (a new operator's try: stale)
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 20, "reset")
            await wait_for(
                pilot, lambda: _selftest_row(app).endswith("| s runs it again"), 10, "fresh"
            )
            assert _selftest_row(app).startswith("stopped the last run stopped before its end")
            kept = read_last("sim")["stopped"]  # what stopped it; its time kept beside
            assert kept["line"] == "by the e-stop", kept

        # a restart: the stopped run is still said first (kept in the state folder)
        again = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with again.run_test(size=size) as pilot:
            pane = again.pane("devices")
            await wait_for(pilot, lambda: bool(pane.doctor_rows), 30, "doctor rows")
            row = _selftest_row(again)
            said = f"stopped the last run stopped before its end (by the e-stop at {kept['time']})"
            assert row.startswith(said), row  # its time said once
            assert row.endswith("| s runs it again"), row

    asyncio.run(scenario())


def test_the_quick_parts_advice_names_the_consoles_key():
    """`haptable doctor`'s skipped quick part advises the CLI (`run `haptable selftest`
    on a healthy table`); the console's row names its own key."""
    from console.tui.selftest_action import selftest_row

    line = "skipped: no baseline yet: run `haptable selftest` on a healthy table to keep one"
    last = {"quick": {"state": "skipped", "line": line, "by": "haptable doctor", "time": "t"}}
    row = selftest_row(None, last)
    assert "press s on a healthy table to keep one" in row.why, row.why
    assert "haptable selftest" not in row.why, row.why
