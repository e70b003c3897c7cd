"""The Devices screen sized to the terminal (a new operator at 80 x 24 in tmux): every
table's columns fit its width, laid out again when the terminal's width changes (End
never scrolls a table sideways, cutting its first column), a long why or fix wraps in its
row or ends in "…", never cut mid-word at the screen's edge; the profile line, and the
line saying what failed under it, are seen on entry."""

from __future__ import annotations

import asyncio

from textual.widgets import DataTable

from console.config.profile import PROJECT_PROFILES
from console.core.types import DeviceStatus
from console.files.paths import shown_path
from console.runtime.context import Context
from console.tui.app import HapTableApp

from .conftest import wait_for

TABLES = ("#device-table", "#audio-table", "#relay-table", "#plugin-table")


def screen_lines(app) -> list[str]:
    return [strip.text for strip in app.screen._compositor.render_strips()]


def _cols_width(table: DataTable) -> int:
    return sum(c.get_render_width(table) for c in table.columns.values())


def _room(table: DataTable) -> int:
    """The columns a table shows its cells in: its width less its own scrollbar (a table
    taller than the screen scrolls within it, the bar over its last columns)."""
    return table.scrollable_content_region.width


async def _listed(app, pilot) -> None:
    await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
    pane = app.pane("devices")
    doc = pane.query_one("#device-table", DataTable)
    cards = pane.query_one("#audio-table", DataTable)
    relays = pane.query_one("#relay-table", DataTable)
    await wait_for(pilot, lambda: doc.row_count >= 7 and cards.row_count >= 2, 30, "doctor")
    await wait_for(pilot, lambda: relays.row_count >= 1, 30, "relay boards")


def test_every_table_fits_the_terminal_after_it_narrows(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(120, 40)) as pilot:
            await _listed(app, pilot)
            pane = app.pane("devices")
            pane.selftest_done = (False, "self-test: table sim: e-stop latched", 3.0)
            pane._show(pane.doctor_rows[:-1])
            await pilot.pause(0.3)
            await pilot.resize_terminal(80, 24)
            for sel in TABLES:
                table = pane.query_one(sel, DataTable)
                await wait_for(
                    pilot,
                    lambda t=table: 0 < _cols_width(t) <= _room(t),
                    10,
                    f"{sel} within {_room(table)} columns",
                )
            doc = pane.query_one("#device-table", DataTable)
            doc.focus()
            await pilot.press("end")
            await pilot.pause(0.2)
            assert doc.scroll_x == 0, doc.scroll_x
            shown = "\n".join(screen_lines(app))
            assert "see log" in shown and " device " in shown, shown

    asyncio.run(scenario())


def test_a_long_fix_wraps_in_its_row_and_a_word_too_long_ends_in_an_ellipsis(plugins):
    long_word = "/a/very/long/path/" + "x" * 70 + "/overrides.toml"
    fix = f"edit the profile's [audio] device, then press d; the file is {long_word}"

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await _listed(app, pilot)
            pane = app.pane("devices")
            row = DeviceStatus("audio", "card", "error", "no such card on this machine", fix)
            pane._show([*pane.doctor_rows[:-1], row])
            doc = pane.query_one("#device-table", DataTable)
            await pilot.pause(0.3)
            assert 0 < _cols_width(doc) <= _room(doc), (_cols_width(doc), _room(doc))
            cols = list(doc.columns.values())
            cell = doc.get_row_at(doc.row_count - 2)[4]  # the self-test's row is last
            lines = str(cell).split("\n")
            assert len(lines) > 1, lines  # wrapped inside its row
            for line in lines:
                assert len(line) <= cols[4].width, (line, cols[4].width)
            assert lines[-1].endswith("…"), lines  # the word too long for the column
            assert "edit the profile's [audio] device, then press d;" in " ".join(lines)

    asyncio.run(scenario())


def test_the_profile_line_and_the_failure_under_it_are_seen_on_entry_at_80x24(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await _listed(app, pilot)
            pane = app.pane("devices")
            cards = pane.query_one("#audio-table", DataTable)
            await wait_for(pilot, lambda: app.focused is cards, 10, "the cards focused")
            await pilot.pause(0.5)
            top = "\n".join(screen_lines(app)[3:8])
            # the profile's path as every message shows it: never relative to the
            # working folder (``shown_path``), whole however it wraps
            shown = f"profile sim ({shown_path(PROJECT_PROFILES / 'sim.toml')})"
            assert shown in " ".join(" ".join(top.split("\n")).split()), top
            pane._show_result("sound card 'x' did not open: no such card", error=True)
            await pilot.pause(0.5)
            lines = screen_lines(app)
            at = [i for i, line in enumerate(lines) if "profile sim (" in line]
            failed = [i for i, line in enumerate(lines) if "did not open" in line]
            assert at and failed and at[0] < failed[0], "\n".join(lines)
            assert app.focused is cards and "twin" in "\n".join(lines), "\n".join(lines)

    asyncio.run(scenario())
