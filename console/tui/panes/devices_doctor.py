"""The Devices screen's device table: `haptable doctor`'s own checks
(``console.runtime.doctor.checks``: the profile's devices, the classifier's files,
real-time memory and scheduling) and the self-test's row, a long why
or fix wrapped inside its row; Enter on a row says it whole."""

from __future__ import annotations

import time
from typing import Any

from rich.markup import escape
from rich.text import Text
from textual.widgets import DataTable

from console.core.types import DeviceStatus
from console.runtime.doctor import checks
from console.tui.device_cells import (
    PROBLEMS,
    ROW_LINES,
    cell_lines,
    note_width,
    reason_lines,
    wrapped_rows,
)
from console.tui.selftest_action import quick_skipped
from console.tui.table_fit import NOTE_MIN, widths
from console.tui.util import from_thread
from console.tui.workers import work


def found(rows) -> str:
    """What a doctor check found, counted by state ("4 simulated, 1 missing")."""
    counts: dict[str, int] = {}
    for s in rows:
        counts[s.state] = counts.get(s.state, 0) + 1
    told = ", ".join(f"{n} {state}" for state, n in counts.items()) or "no devices"
    bad = any(state in ("missing", "error") for state in counts)
    return told + ("; the fix column says what to do" if bad else "")


#: a device's states that ask nothing of the operator: their rows may take one line
WORKS = ("ok", "simulated", "not run")


class DevicesDoctorMixin:
    """The device table of ``DevicesPane`` (its status line ``_show_result``/``_say``,
    ``_profile``, ``_table_width`` and the self-test's row ``_selftest_status``)."""

    app: Any
    doctor_rows: list[DeviceStatus]
    audio_rows: dict[str, tuple[str, str]]
    _doctor_whole: bool
    quick_skips: str

    @work(thread=True, exclusive=True, group="doctor")
    def action_doctor(self, said: bool = False) -> None:
        """Re-check the profile's devices; ``said`` (the key d): the status line says
        it is checking, then what the check found."""
        try:
            app = self.app
            prof = self._profile()
        except RuntimeError:  # Textual's NoActiveAppError: the console closed before this ran
            return
        if said:
            self._say("re-checking the profile's devices ...")
        # `haptable doctor`'s own checks; its quick self-test plays: here s runs the
        # full one, and the row says the quick part's skip as doctor would
        rows = checks(prof, app.ctx.pm)
        from_thread(app, self._show, rows, said, quick_skipped(prof, app.ctx.pm))

    def _show(self, rows, said: bool = False, skips: str | None = None) -> None:
        """The device table of ``rows`` and the self-test's row; ``skips``: the doctor's
        quick part's skip as checked now (None: as last checked)."""
        if not self.query("#device-table"):  # a worker finishing while the console closes
            return
        if skips is not None:
            self.quick_skips = skips
        if said:
            self._show_result(f"devices re-checked at {time.strftime('%H:%M:%S')}: {found(rows)}")
        self.doctor_rows = rows = [*rows, self._selftest_status()]
        table = self.query_one("#device-table", DataTable)
        table.clear(columns=True)
        firsts = [[s.kind, s.name, s.state] for s in rows]
        heads = ("device", "driver", "state")
        # each first column as wide as its widest word, given, not left to the table: an
        # auto width grows as rows come and the rows drawn before kept the narrower one
        # (``simul``/``ated``, the fix cut at the screen's edge: ``press s (full``)
        for head, width in zip(heads, widths(heads, firsts), strict=True):
            table.add_column(head, width=width)
        # why and fix share what the first columns leave, the fix whole first (it says
        # what to do); a longer text wraps inside its cell: the row grows, nothing is cut
        left = note_width(table, firsts, self._table_width(), heads)
        why_w, fix_w, cells, heights = self._fit_rows(rows, left, table.has_focus)
        top = self.query_one("#devices-top").outer_size.height  # docked: always there
        if sum(heights) + 1 > self.scrollable_content_region.height - top:
            # rows taller than the screen under its top lines (whole, or a problem's and
            # a reason's kept whole): the table scrolls, its scrollbar takes columns the
            # fix had (``press s (full`` cut under it)
            gutter = table.styles.scrollbar_size_vertical
            left = max(NOTE_MIN, left - gutter)
            why_w, fix_w, cells, heights = self._fit_rows(rows, left, table.has_focus)
        table.add_column("why", width=why_w)
        table.add_column("fix", width=fix_w)
        for s, (why, fix), lines in zip(rows, cells, heights, strict=True):
            state = {"ok": "[green]ok[/]", "simulated": "[cyan]simulated[/]"}.get(
                s.state, f"[red]{escape(s.state)}[/]"
            )
            table.add_row(
                Text(s.kind), Text(s.name), Text.from_markup(state), why, fix, height=lines
            )
        self._keep_focused_in_view()  # the rows above a list grew

    def _fit_rows(self, rows, left: int, whole: bool):
        """(why width, fix width, cells, heights) of ``rows`` within ``left`` columns:
        whole when ``whole`` (the table focused) or when they leave the card in use in
        view (``_doctor_room``), else shortened (below)."""
        why_w, fix_w, cells, heights = wrapped_rows(rows, left)
        # wrapped here (a row's height known as it is added: the list below it is
        # scrolled into view at once), a number with its unit on one line, a word too
        # long for its column ending in "…"; when wrapped rows would push the card in use
        # out of view (on entry: the card list has the focus), a row that works takes one
        # line, a problem's row stays whole (what to do), any other row two lines at
        # most or those its reason takes, cut after it (a word: in the log, Enter says
        # it; a doctor's skipped self-test took ten lines and the screen opened scrolled
        # down; cut to two it read ``skipped (haptable doctor…)``, its reason gone); the
        # table focused (Tab) shows every row whole
        self._doctor_whole = whole or sum(heights) <= self._doctor_room()
        if self._doctor_whole:
            return why_w, fix_w, cells, heights
        for i, s in enumerate(rows):  # works: one line; a problem: whole; else two at
            # most, or the lines its reason takes, cut after it
            most = 1 if s.state in WORKS else max(ROW_LINES, reason_lines(s.why, why_w))
            if s.state not in PROBLEMS and heights[i] > most:
                why = cell_lines(s.why, f"{s.kind} {s.name}", why_w, most)
                fix = cell_lines(s.fix, f"{s.kind} {s.name}", fix_w, most)
                cells[i] = (why, fix)
                heights[i] = max(len(why.plain.split("\n")), len(fix.plain.split("\n")))
        return why_w, fix_w, cells, heights

    def _doctor_room(self) -> int:
        """The lines the device table's rows may take for the screen to show, from its
        top, the table's header and the sound-card list down to the card in use (its
        heading, header, the rows up to it, the blank line before the heading)."""
        top = self.query_one("#devices-top").outer_size.height
        cards = list(self.audio_rows.values())
        in_use = self._in_use()[:2]
        upto = cards.index(in_use) + 1 if in_use in cards else max(len(cards), 2)
        height = self.size.height or self.app.size.height - 5
        return height - top - 1 - (3 + upto)

    def _about_device(self, event: DataTable.RowSelected) -> None:
        """Enter on a device's row: its whole line on the status line (the screen's
        ``on_data_table_row_selected``: ``DevicePicksMixin``)."""
        if 0 <= event.cursor_row < len(self.doctor_rows):
            s = self.doctor_rows[event.cursor_row]
            fix = f"; fix: {s.fix}" if s.fix else ""
            self._show_result(f"{s.kind} {s.name}: {s.state}: {s.why}{fix}")
