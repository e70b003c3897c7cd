"""Devices (F1) after `haptable doctor` ran in a shell, at 80 x 24 and 120 x 40: the
screen opens on its top (the profile line, the device table's header) with the card in
use in view, each device row a line or two (the doctor's skipped quick self-test wrapped
over ten lines and pushed the screen down to the `realtime memory` row), the self-test's
the lines its reason takes (cut to two it read `(haptable doctor…)`), and the row's
hint whole (`press s (full)`, once cut `press s (full …`), read in its column; Enter on a
shortened row says it whole (a new operator's try)."""

from __future__ import annotations

import asyncio
from itertools import takewhile

import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.shorten import balanced

from .conftest import wait_for
from .test_camera_layout import screen_lines
from .test_devices_selftest_what_ran import _haptable


def _has(app, *words: str) -> bool:
    return any(all(w in line for w in words) for line in screen_lines(app))


def _fix_cells(shown: list[str]) -> list[str]:
    """What the device table's fix column shows on each line of the self-test's row:
    the text under the header's ``fix`` (the why beside it says ``press s on a healthy
    table`` too, on a line of its own at 120 columns: a line holding ``press s`` is no
    fix)."""
    head = next(ln for ln in shown if all(w in ln for w in ("device", "why", "fix")))
    why_x, fix_x = head.index(" why ") + 1, head.index(" fix ") + 1
    first = next(i for i, ln in enumerate(shown) if "selftest" in ln and "quick" in ln)
    more = takewhile(lambda ln: ln.strip() and not ln[:why_x].strip(), shown[first + 1 :])
    cells = [" ".join(ln[fix_x:].split()) for ln in [shown[first], *more]]
    return [c for c in cells if c]


def shell_doctor_skips() -> None:
    """`haptable doctor` run in a shell: no baseline yet, its quick self-test skipped
    and said why."""
    doctor = _haptable("doctor")
    assert "selftest   quick        skipped   skipped: no baseline yet" in doctor.stdout, (
        doctor.stdout
    )


async def devices_listed(app, pilot, cards: int = 2) -> DataTable:
    """The device table once ``cards`` sound cards are listed and the devices checked."""
    audio = app.query_one("#audio-table", DataTable)
    table = app.query_one("#device-table", DataTable)
    await wait_for(pilot, lambda: audio.row_count >= cards, 30, "sound cards listed")
    await wait_for(pilot, lambda: table.row_count >= 7, 30, "the devices checked")
    return table


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_devices_after_a_shell_doctor_opens_on_its_top(plugins, size):
    shell_doctor_skips()

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            table = await devices_listed(app, pilot)
            await wait_for(pilot, lambda: _has(app, "●", "twin"), 10, "the card in use")
            await pilot.pause(0.5)  # laid out
            shown = screen_lines(app)
            assert app.pane("devices").scroll_y == 0, "\n".join(shown)
            assert _has(app, "profile sim"), "\n".join(shown)
            assert _has(app, "device", "driver", "state", "why"), "\n".join(shown)
            assert _has(app, "selftest", "quick", "skipped"), "\n".join(shown)
            assert _has(app, "press s (full)"), "\n".join(shown)
            # the fix cell whole, on its row's first line (a list as the assertion's
            # message is shortened in its middle by pytest: "press s (full...")
            assert _fix_cells(shown) == ["press s (full)"], "\n".join(shown)
            if size[0] == 80:  # too many lines whole: a line or two each, the self-test's
                heights = [table.rows[k].height for k in table.rows]  # its reason's
                assert max(heights[:-1]) <= 2, heights
                # shortened after its reason (what to act on), every bracket closed
                why = " ".join(str(table.get_row_at(table.row_count - 1)[3]).split())
                assert balanced(why) and why.endswith("…"), why
                assert "(no baseline yet: press s on a healthy table to keep one)" in why
            # the self-test row, shortened: Enter says it whole
            table.focus()
            await pilot.pause(0.2)  # focused: its rows laid out whole again
            table.move_cursor(row=table.row_count - 1)
            await pilot.pause(0.1)
            await pilot.press("enter")
            said = " ".join(str(app.query_one("#devices-result").render()).split())
            assert "on a healthy table to keep one" in said, said

    asyncio.run(scenario())
