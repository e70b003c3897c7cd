"""Devices: the profile, each device with its doctor status and fix, the sound card and
relay board to use (picked here, saved to the profile's override file, the outputs
reopened with them), a named test signal through the gate, and every plugin."""

from __future__ import annotations

import math
import time
from typing import Any

from rich.markup import escape
from rich.text import Text
from textual import on, work
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical, VerticalScroll
from textual.widgets import DataTable, Select, Static

from console.config.profile import overrides_path
from console.core.errors import UserError
from console.core.types import DeviceStatus
from console.runtime.devices import output_devices, relay_boards
from console.runtime.doctor import diagnose, realtime_status, scheduling_status
from console.runtime.selftest_last import forget_last, note_last, read_last
from console.session.events import ESTOP_FIX, Started, Stopped, estop_refusal
from console.signals.stimuli import STIMULI, make_stimulus
from console.tui.ask_again import AskAgain
from console.tui.device_cells import (
    PROBLEMS,
    ROW_LINES,
    cell,
    cell_lines,
    note_room,
    note_width,
    wrapped_rows,
)
from console.tui.device_picks import DevicePicksMixin
from console.tui.focus_keys import show_keys
from console.tui.kept_text import KeptText
from console.tui.lapse import lapse_if_held
from console.tui.long_work import NOTE_S
from console.tui.question_hold import waits_for_question
from console.tui.said import status_said
from console.tui.selftest_action import (
    run_selftest,
    selftest_about,
    selftest_progress,
    selftest_row,
)
from console.tui.session_messages import SessionMessage
from console.tui.table_fit import NOTE_MIN, need, share, widths
from console.tui.text import LiteralTable
from console.tui.util import from_thread, short_path

#: the plugins table's description column at least (at 80 columns: the table fits)
PLUGIN_DESC_MAX = 24
#: the sound-card table's device column at most (the note takes what the other columns
#: leave of the screen's width)
DEVICE_MAX = 23


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
#: a relay board's probe states in which enter opens nothing (it says why instead)
UNUSABLE = ("missing", "error")


def listed(audio, relays) -> str:
    """What a listing found ("1 sound card, 3 relay boards, 1 missing")."""
    cards = sum(len(d.devices) for d in audio)
    told = [_many(cards, "sound card"), _many(len(relays), "relay board")]
    bad: dict[str, int] = {}
    for _, _, status in relays:
        if status.state in UNUSABLE:
            bad[status.state] = bad.get(status.state, 0) + 1
    return ", ".join(told + [f"{n} {state}" for state, n in bad.items()])


def _many(n: int, what: str) -> str:
    return f"{n} {what}{'' if n == 1 else 's'}"


def _ms(seconds: float) -> str:
    return "-" if seconds is None or not math.isfinite(seconds) else f"{seconds * 1e3:.1f}"


def _note(dev) -> str:
    """A card's note, "default" first for the system's default output."""
    return "; ".join(n for n in ("default" if dev.default else "", dev.note) if n)


def _latency(low_s: float, high_s: float) -> str:
    """A card's default low and high latency in ms, "low/high" as the column's head
    says (never "low-high": it reads as a range); "-" when unknown."""
    low, high = _ms(low_s), _ms(high_s)
    return "-" if low == high == "-" else f"{low}/{high}"


#: the sound cards' latency column: which number is which (``_latency``)
LATENCY_HEAD = "low/high ms"


#: the relay boards' table's column heads
RELAY_HEADS = ("", "driver", "probe", "what it finds", "description")


#: how the line says the operator reset the e-stop (a new e-stop replaces it)
RESET = "e-stop reset"


#: the test signal's heading: how one is chosen and what ``t`` does with it
TEST_SIGNAL_HEADING = "test signal (Tab here, enter lists them; t plays the chosen one)"


def _says_estop(line: str) -> bool:
    """Whether ``line`` says the e-stop is active (stale once the operator reset it)."""
    words = ("e-stop active", "e-stop is active", "e-stop latched", "ctrl+r resets")
    return any(w in line for w in words)


class DevicesPane(DevicePicksMixin, VerticalScroll):
    #: no Tab stop of its own (it would only scroll, naming no key): the focused list
    #: scrolls into view, and the screen's keys work from each of them
    can_focus = False
    HELP_TEXT = (
        "enter    on a sound card or relay board row: enter again within 3 s uses it (saved\n"
        "         to the profile's override file; the outputs reopen with it); on the one\n"
        "         in use (●): nothing changes\n"
        "t        play the chosen test signal through the gate on the outputs now open (choose\n"
        "         it under 'test signal': Tab to the drop-down, enter lists the signals)\n"
        "l        list the sound cards and relay boards again\n"
        "d        re-check the profile's devices (doctor)\n"
        "s        self-test: s again within 3 s chirps every relay path, compares with\n"
        "         the baseline"
    )
    BINDINGS = [
        # short words: every key shows in the footer at 80 columns, a table's Enter first
        Binding("d", "doctor(True)", "doctor"),
        Binding("l", "list_devices(True)", "list"),
        Binding("t", "test_output", "test"),
        Binding("s", "selftest", "self-test"),
    ]

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.audio_rows: dict[str, tuple[str, str]] = {}  # row key -> (driver, device)
        self.no_device_rows: dict[str, str] = {}  # row key -> why it cannot be picked
        self.relay_rows: dict[str, str] = {}  # row key -> driver
        #: row key -> its probe's status when the board cannot be opened (missing, error)
        self.unusable_boards: dict[str, DeviceStatus] = {}
        self.plugin_rows: dict[str, str] = {}  # row key -> the plugin's line, whole
        self._listed: tuple | None = None  # the sound cards and boards the tables show
        self._listing: tuple | None = None  # the last listing (audio, relays), laid out
        self._laid_out = 0  # the width the tables are laid out for
        self.result = ""  # the last pick or test, as shown
        self.doctor_rows: list[DeviceStatus] = []  # the doctor's rows, as shown
        #: the self-test's row: its last run here (None: not run), its seconds then
        self.selftest_done: tuple[bool, str, float] | None = None
        #: the last run here stopped before its end: when and by what ("" : it was not)
        self.selftest_stopped = ""
        self._selftest_timer = None  # the self-test's progress ticks while it runs
        #: the self-test's start (monotonic s), seconds expected and estimate, for ticks
        self._selftest_clock: tuple[float, float, Any] = (0.0, 0.0, None)
        self._answered_at = 0.0  # when a key last answered while the self-test runs
        self._estopped_at_start = False  # the self-test began during an e-stop (refused)
        self.ask = AskAgain()  # a pick and the self-test: their key again does it
        self._doctor_whole = True  # the device table's rows shown whole (``_show``)

    def compose(self) -> ComposeResult:
        # the profile line and under it the screen's status line (what a pick or a test
        # did): docked at the top, seen on entry and wherever the lists are scrolled
        with Vertical(id="devices-top"):
            yield KeptText(id="profile-line", markup=False)
            result = KeptText("", id="devices-result", markup=False)  # a number, its unit
            result.display = False  # shown once it has something to say
            yield result
        # each table's Enter first in the footer while it has the focus
        yield show_keys(LiteralTable(id="device-table", cursor_type="row"), enter="whole row")
        yield Static(
            f"sound card (enter uses it; saved to the profile; {LATENCY_HEAD}: its latency)",
            classes="heading",
        )
        yield show_keys(LiteralTable(id="audio-table", cursor_type="row"), enter="use")
        yield Static("relay board (enter uses it)", classes="heading")
        yield show_keys(LiteralTable(id="relay-table", cursor_type="row"), enter="use")
        # how to choose one, where it is chosen (a new operator found only sine-PA played)
        yield Static(TEST_SIGNAL_HEADING, classes="heading")
        yield show_keys(
            Select(
                [(f"{name}: {desc}", name) for name, (desc, _) in STIMULI.items()],
                value="sine-PA",
                allow_blank=False,
                id="stimulus",
            ),
            enter="test signals",
        )
        yield Static("plugins and what they provide", classes="heading")
        yield show_keys(LiteralTable(id="plugin-table", cursor_type="row"), enter="whole row")

    @property
    def focus_target(self):
        """The sound cards: the list Up/Down and Enter act on, from the screen's first
        key (the doctor's table above it takes no Enter)."""
        return self.query_one("#audio-table", DataTable)

    def on_show(self) -> None:
        """Shown again: the profile line says what is saved now (another screen's ``u``
        or ``W`` may have written the settings file meanwhile)."""
        self._show_profile_line()

    def on_mount(self) -> None:
        self._show_profile_line()
        self.query_one("#audio-table", DataTable).add_columns(
            "", "driver", "device", "host API", "ch", LATENCY_HEAD, "note"
        )
        self.query_one("#relay-table", DataTable).add_columns(*RELAY_HEADS)
        self._fill_plugins()
        self.call_after_refresh(self.action_doctor)
        self.call_after_refresh(self.action_list_devices)

    def _fill_plugins(self) -> None:
        """The plugins table, its description sized to the width the table has."""
        ctx = self.app.ctx
        plug = self.query_one("#plugin-table", DataTable)
        plug.clear(columns=True)
        plug.add_columns("kind", "name", "plugin", "description")
        regs = [
            (kind, name, reg)
            for kind, by_name in sorted(ctx.pm.registrations.items())
            for name, reg in sorted(by_name.items())
            if reg.tab is None  # a screen of the console: its tab shows it
        ]
        # the description takes what the other columns leave of the screen (each column
        # has a cell of padding either side), at least PLUGIN_DESC_MAX
        cells = [(kind, name, reg.plugin) for kind, name, reg in regs]
        others = sum(max(map(len, col), default=0) + 2 for col in zip(*cells, strict=True))
        width = max(PLUGIN_DESC_MAX, self._table_width() - others - 4)
        for kind, name, reg in regs:
            key = f"{kind}\x00{name}"
            self.plugin_rows[key] = f"{kind} {name} ({reg.plugin}): {reg.description}"
            about = cell(reg.description, f"{kind} {name}", width)
            plug.add_row(Text(kind), Text(name), Text(reg.plugin), about, key=key)

    def _table_width(self) -> int:
        """The width every table has: the screen's less its scrollbar's gutter (kept
        whether or not the lists overflow); the terminal's while the screen is hidden."""
        return self.scrollable_content_region.width or self.app.size.width - 2

    def on_resize(self, event) -> None:
        """The terminal's width changed (tmux resized, a window dragged): every table laid
        out again within it (a table wider than the screen scrolls, cutting its first)."""
        width = self._table_width()
        if width == self._laid_out:
            return
        self._laid_out = width
        self._fill_plugins()
        if self.doctor_rows:
            self._show(self.doctor_rows[:-1])
        if self._listing is not None:
            self._show_devices(*self._listing)

    # ------------------------------------------------------------------ what is in use
    def _profile(self):
        """The profile the outputs open with (after a pick: reloaded with it)."""
        session = self.app.session
        return session.outputs_profile or self.app.ctx.profile

    def _show_profile_line(self) -> None:
        prof = self._profile()
        # the saved settings' file as it is now (other screens' help points here for
        # its path; ``u``, ``W``, a pick write it while this console runs)
        over = overrides_path(prof.name)
        saved = (
            f"; saved settings: {short_path(over)}" if over.exists() else "; no saved settings yet"
        )
        about = (prof.get("profile.description") or "").strip().rstrip(".")
        self.query_one("#profile-line", Static).update(
            f"profile {prof.name} ({short_path(prof.path)}): {about}{saved}"
        )
        self.call_after_refresh(self._focused_in_view)

    def _in_use(self) -> tuple[str, str, str]:
        prof = self._profile()
        return prof.get("audio.driver"), prof.get("audio.device") or "", prof.get("relays.driver")

    # ------------------------------------------------------------------ doctor
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
        # the same checks as `haptable doctor`; its quick self-test plays: here s runs it
        rows = [*diagnose(prof, app.ctx.pm), realtime_status(prof, app.ctx.pm)]
        rows += [scheduling_status(prof, app.ctx.pm)]
        from_thread(app, self._show, rows, said)

    def _show(self, rows, said: bool = False) -> None:
        if not self.query("#device-table"):  # a worker finishing while the console closes
            return
        if said:
            self._show_result(f"devices re-checked at {time.strftime('%H:%M:%S')}: {found(rows)}")
        last = read_last(self._profile().name)  # `haptable doctor`'s quick part too
        out = self.app.session.outputs
        estopped = out is not None and out.estopped
        # a run stopped here, or in an earlier session of the console (kept in the file)
        kept = last.get("stopped")
        stopped = self.selftest_stopped or (f"{kept['line']}, {kept['time']}" if kept else "")
        row = selftest_row(self.selftest_done, last, stopped, estopped)
        self.doctor_rows = rows = [*rows, row]
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
        why_w, fix_w, cells, heights = wrapped_rows(rows, left)
        if table.has_focus and sum(heights) + 1 > self.scrollable_content_region.height:
            # whole rows taller than the screen: the table scrolls, its scrollbar takes
            # columns the fix had (``press s (full`` cut under it)
            gutter = table.styles.scrollbar_size_vertical
            why_w, fix_w, cells, heights = wrapped_rows(rows, max(NOTE_MIN, left - gutter))
        table.add_column("why", width=why_w)
        table.add_column("fix", width=fix_w)
        # wrapped here (a row's height known as it is added: the list below it is
        # scrolled into view at once), a number with its unit on one line, a word too
        # long for its column ending in "…"; when wrapped rows would push the card in use
        # out of view (on entry: the card list has the focus), a row that works takes one
        # line, a problem's row stays whole (what to do), any other row two lines at
        # most (cut after a word: in the log, Enter says it; a doctor's skipped
        # self-test took ten lines and the screen opened scrolled down); the table
        # focused (Tab) shows every row whole
        self._doctor_whole = table.has_focus or sum(heights) <= self._doctor_room()
        if not self._doctor_whole:  # works: one line; a problem: whole; else two at most
            for i, s in enumerate(rows):
                most = 1 if s.state in WORKS else ROW_LINES
                if s.state not in PROBLEMS and heights[i] > most:
                    why = cell_lines(s.why, f"{s.kind} {s.name}", why_w, most)
                    fix = cell_lines(s.fix, f"{s.kind} {s.name}", fix_w, most)
                    cells[i] = (why, fix)
                    heights[i] = max(len(why.plain.split("\n")), len(fix.plain.split("\n")))
        for s, (why, fix), lines in zip(rows, cells, heights, strict=True):
            state = {"ok": "[green]ok[/]", "simulated": "[cyan]simulated[/]"}.get(
                s.state, f"[red]{escape(s.state)}[/]"
            )
            table.add_row(
                Text(s.kind), Text(s.name), Text.from_markup(state), why, fix, height=lines
            )
        self._keep_focused_in_view()  # the rows above a list grew

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

    @on(DataTable.RowSelected, "#device-table")
    def _about_device(self, event: DataTable.RowSelected) -> None:
        """Enter on a device's row: its whole line on the status line."""
        if 0 <= event.cursor_row < len(self.doctor_rows):
            s = self.doctor_rows[event.cursor_row]
            fix = f"; fix: {s.fix}" if s.fix else ""
            self._show_result(f"{s.kind} {s.name}: {s.state}: {s.why}{fix}")

    # ------------------------------------------------------------------ listing
    @work(thread=True, exclusive=True, group="devices")
    def action_list_devices(self, said: bool = False) -> None:
        """List the sound cards and relay boards again; ``said`` (the key l): the status
        line says it is listing, then what the listing found."""
        try:
            app = self.app
            prof, pm = self._profile(), app.ctx.pm
        except RuntimeError:  # Textual's NoActiveAppError: the console closed before this ran
            return
        if said:
            self._say("listing the sound cards and relay boards ...")
        audio = output_devices(prof, pm)
        status, _log = app.live.now  # the board the outputs process holds is not probed
        relays = relay_boards(prof, pm, held=(status or {}).get("relays"))
        from_thread(app, self._show_devices, audio, relays, said)

    def _audio_row(
        self, d, dev, drv: str, device: str, device_w: int = DEVICE_MAX
    ) -> tuple[str, list, tuple[str, str]]:
        """(key, cells but the note, (note, whose)) of sound card ``dev`` of driver
        ``d`` (``dev`` None: the driver found none), its name within ``device_w``; the
        card in use marked ●, the system's default one in its note."""
        if dev is None:
            key = f"{d.driver}\x00"
            self.audio_rows[key] = (d.driver, "")
            if d.lists:  # it lists its devices and found none: nothing to open
                self.no_device_rows[key] = f"{d.driver}: {d.problem}"
            none = cell(f"none: {d.problem}", f"sound card driver {d.driver}", device_w)
            mark = "●" if d.driver == drv else ""
            return key, [mark, Text(d.driver), none, "", "", ""], ("", "")
        key = f"{dev.driver}\x00{dev.name}"
        self.audio_rows[key] = (dev.driver, dev.name)
        used = dev.driver == drv and (drv == "twin" or dev.name == device)
        return (
            key,
            [
                "●" if used else "",
                Text(dev.driver),
                cell(dev.name, f"sound card {dev.driver}", device_w),
                cell(dev.host_api, f"sound card {dev.name}: host API", 12),
                str(dev.output_channels),
                _latency(dev.low_latency_s, dev.high_latency_s),
            ],
            (_note(dev), f"sound card {dev.name}: note"),
        )

    def _first_usable(self, rows) -> int:
        """The row the sound-card cursor starts on: the card in use (●), else the first
        Enter can use (a driver that found no card is no place to start)."""
        marked = [i for i, (_k, cells, _n) in enumerate(rows) if cells[0] == "●"]
        usable = [i for i, (key, _c, _n) in enumerate(rows) if key not in self.no_device_rows]
        return (marked or usable or [0])[0]

    def _show_devices(self, audio, relays, said: bool = False) -> None:
        if not self.query("#audio-table"):  # a worker finishing while the console closes
            return
        if said:
            self._show_result(
                f"listed again at {time.strftime('%H:%M:%S')}: {listed(audio, relays)}"
            )
        self._listing = (audio, relays)
        drv, device, relay_drv = self._in_use()
        table = self.query_one("#audio-table", DataTable)
        self.audio_rows.clear()
        self.no_device_rows.clear()
        rows = [self._audio_row(d, dev, drv, device) for d in audio for dev in d.devices or [None]]
        # a narrow screen: the device's name gives up what the note needs (a long name,
        # JACK's, would push the table past the screen's edge)
        heads = [str(c.label) for c in table.columns.values()]
        over = NOTE_MIN - note_room(
            table, [c for _k, c, _n in rows], self._table_width(), heads[:-1]
        )
        if over > 0:
            device_w = max(NOTE_MIN, DEVICE_MAX - over)
            self.audio_rows.clear()
            self.no_device_rows.clear()
            rows = [
                self._audio_row(d, dev, drv, device, device_w)
                for d in audio
                for dev in d.devices or [None]
            ]
        shown = (
            repr(rows),
            repr([(n, d, st.state, st.why) for n, d, st in relays]),
            relay_drv,
            self._table_width(),
        )
        if shown == self._listed:  # the same listing: the tables stay as they are (a
            return  # rebuilt table lays its columns out again at its next idle)
        self._listed = shown
        note_w = note_width(
            table, [cells for _key, cells, _note in rows], self._table_width(), heads[:-1]
        )
        full = [
            (key, [*cells, cell(note, where, note_w) if note else ""])
            for key, cells, (note, where) in rows
        ]
        # each column as wide as its widest cell, given: the header is drawn with the rows'
        # widths at once (widths DataTable measures itself reach the header only at a
        # later refresh, which a quiet screen may not get: misaligned headings)
        table.clear(columns=True)
        for head, width in zip(heads, widths(heads, [cells for _k, cells in full]), strict=True):
            table.add_column(head, width=width)
        for key, cells in full:
            table.add_row(*cells, key=key)
        table.move_cursor(row=self._first_usable(rows), animate=False)
        self._keep_focused_in_view()  # the list grew: the focused one is seen whole
        rtable = self.query_one("#relay-table", DataTable)
        rtable.clear(columns=True)  # widths from this listing (a column never shrinks)
        self.relay_rows.clear()
        self.unusable_boards.clear()
        firsts = [["●", name, status.state] for name, _d, status in relays]
        # what it finds and the description share what the first columns leave
        finds_w, desc_w = share(
            note_width(rtable, firsts, self._table_width(), RELAY_HEADS[:3]),
            (
                need("what it finds", [st.why for _n, _d, st in relays]),
                need("description", [d for _n, d, _s in relays]),
            ),
        )
        for head, width in zip(
            RELAY_HEADS, [*widths(RELAY_HEADS[:3], firsts), finds_w, desc_w], strict=True
        ):
            rtable.add_column(head, width=width)
        for name, description, status in relays:
            key = f"relay\x00{name}"
            self.relay_rows[key] = name
            if status.state in UNUSABLE:  # its probe found nothing it can open
                self.unusable_boards[key] = status
            rtable.add_row(
                "●" if name == relay_drv else "",
                Text(name),
                Text(status.state),
                cell(status.why, f"relay board {name}", finds_w),
                cell(description, f"relay board {name}: description", desc_w),
                key=key,
            )

    # ------------------------------------------------------------------ testing
    @work(thread=True, exclusive=True, group="test-output")
    def action_test_output(self) -> None:

        name = from_thread(self.app, lambda: self.query_one("#stimulus", Select).value)
        session = self.app.session
        prof = self._profile()
        try:
            plan = make_stimulus(
                str(name),
                int(prof.get("audio.sample_rate_hz")),
                float(prof.get("limits.max_plan_s")),
            )
        except UserError as exc:
            self._say(f"test signal: {exc}", error=True)
            return
        where = prof.get("audio.device") or prof.get("audio.driver")
        self._say(f"{name}: asking to play on {where!r} ...")
        outcome = session.play(
            plan, on_started=lambda: self._say(f"{name}: playing on {where!r} ...")
        )
        if not outcome.played:  # the line says what became of it, from the outcome
            why = outcome.refused or f"stopped by {outcome.stopped}"
            self._say(f"{name} on {where!r}: {why}", error=True)
            return
        trace = session.scope(plan.duration_s + 0.5)
        peaks = (
            ""
            if trace is None
            else ", ".join(f"{ch} {v:.1f} V peak" for ch, v in trace.peak_v().items())
        )
        self._say(f"{name} played on {where!r} through the gate: {peaks}")

    def action_selftest(self) -> None:
        """``s``: asks first, saying its paths and time (it plays chirps on every relay
        path), ``s`` again within 3 s runs it; refused at once during an e-stop."""
        out = self.app.session.outputs
        if out is not None and out.estopped:  # nothing to ask: the console's key first
            self._show_result(f"self-test {estop_refusal(out.estop_reason or '')}", error=True)
            return
        if self.ask.confirmed("selftest"):
            self._selftest()
            return
        last_s = self.selftest_done[2] if self.selftest_done else 0.0
        about = selftest_about(self._profile(), self.app.ctx.pm, last_s)[0]
        does = f"runs the self-test ({about}): a chirp on every relay path"
        self.ask.ask(self, "s", does, lambda: self.result, self._show_result)

    @work(thread=True, exclusive=True, group="test-output")
    def _selftest(self) -> None:
        """Every relay path chirped and compared (``console.tui.selftest_action``): the
        line says how long it takes before it starts, then how far it is."""
        prof, pm = self._profile(), self.app.ctx.pm
        last_s = self.selftest_done[2] if self.selftest_done else 0.0
        about, total_s, est = selftest_about(prof, pm, last_s)
        out = self.app.session.outputs
        self._estopped_at_start = out is not None and out.estopped
        self._say(f"self-test ({about}): starting ...")
        t0 = time.monotonic()
        from_thread(self.app, self._selftest_ticks, t0, total_s, est)
        ok, line = run_selftest(prof, pm)
        if ok is not None:  # it ran: kept for the row after a restart
            note_last(prof.name, "full", "ok" if ok else "error", line, "the console's s")
        took_s = 0.0 if est and est[2] else time.monotonic() - t0  # a map run: no guide
        from_thread(self.app, self._selftest_ended, ok, line, took_s)

    def _selftest_ticks(self, t0: float, total_s: float, est) -> None:
        """While the self-test runs: the line says what it does and the time left
        (``selftest_progress``)."""

        self._selftest_clock = (t0, total_s, est)
        self._answered_at = 0.0
        self._selftest_timer = self.set_interval(0.5, self._selftest_tick)

    def _selftest_tick(self) -> None:
        """The self-test's progress on the line, unless a key answered on it less than
        ``NOTE_S`` ago (a tick every 0.5 s took ``d``'s answer before it was read)."""
        if time.monotonic() - self._answered_at < NOTE_S:
            return
        t0, total_s, est = self._selftest_clock
        self._show_result(selftest_progress(time.monotonic() - t0, total_s, est), tick=True)

    def _selftest_ended(self, ok: bool | None, line: str, took_s: float) -> None:
        prof_name = self._profile().name
        if self._selftest_timer is not None:
            self._selftest_timer.stop()
            self._selftest_timer = None
        if ok is None:  # refused (the row keeps the last result) or stopped under way
            out = self.app.session.outputs
            at = time.strftime("%H:%M:%S")
            if out is not None and out.estopped and not self._estopped_at_start:
                # under way when the e-stop came: stopped, not refused; the reset's line
                # replaces this one (``_says_estop``)
                line = f"self-test stopped by the e-stop before its end; {ESTOP_FIX}, then s"
                line += " runs it again"
                self.selftest_stopped = f"by the e-stop at {at}"
            elif line.startswith("self-test stopped"):
                self.selftest_stopped = f"at {at}: {line.split('(', 1)[-1].rstrip(')')}"
            if self.selftest_stopped:  # kept for the row after a restart
                note_last(prof_name, "stopped", "stopped", self.selftest_stopped, "the console's s")
            if self.selftest_stopped and self.doctor_rows:  # the row says it too: its
                self._show(self.doctor_rows[:-1])  # last outcome is not this run's
            self._show_result(line, error=True)
            return
        self.selftest_done, self.selftest_stopped = (ok, line, took_s), ""
        forget_last(prof_name, "stopped")  # a whole run ended: the stopped one is past
        self._show_result(line, error=not ok)
        if self.doctor_rows:  # its row in the devices table says it too
            self._show(self.doctor_rows[:-1])

    @waits_for_question
    def _show_result(
        self, text: str, error: bool = False, severity: str = "", tick: bool = False
    ) -> None:
        """The screen's status line, the newest message replacing it: docked at the
        top of the screen, in view wherever the list is scrolled (a pick on a row far
        down says what it did where it is seen); an error or a refusal (``severity``
        ``warning``) is in the log too. While the self-test runs, a message that is not
        its ``tick`` holds the line ``NOTE_S`` against the ticks."""
        if not tick and self._selftest_timer is not None:
            self._answered_at = time.monotonic()
        severity = "error" if error else severity
        self.result = text
        found = self.query("#devices-result")
        if found:
            line = found.first(Static)
            line.update(text)
            line.display = bool(text)
            line.set_class(error, "error")
            status_said(line, "Devices", text, severity or "information")
            # a refusal because a run holds the outputs leaves the line when it ends
            lapse_if_held(self, self.app.session, lambda: self.result, text, self._show_result)
            self.call_after_refresh(self._focused_in_view)

    def on_session_message(self, message: SessionMessage) -> None:
        """The operator's reset (``Started`` on topic ``estop``): a line saying what the
        e-stop refused is past; it says the reset instead. A new e-stop (``Stopped``)
        replaces a line saying the reset: it is latched again."""
        ev = message.event
        if ev.topic == "estop" and self.doctor_rows:  # a stopped run's row (this session's
            self._show(self.doctor_rows[:-1])  # or kept): ctrl+r first or not
        if isinstance(ev, Started) and ev.topic == "estop" and _says_estop(self.result):
            self._show_result(f"{RESET}: t plays the test signal, enter picks a row")
        elif isinstance(ev, Stopped) and ev.topic == "estop" and self.result.startswith(RESET):
            # latched again: the line saying the reset is no longer true
            why = " ".join(ev.reason.split())
            self._show_result(f"e-stop active{': ' + why if why else ''}; {ESTOP_FIX}", True)

    def _keep_focused_in_view(self) -> None:
        """``_focused_in_view`` once a table's new rows are laid out (the table sizes
        itself on its own refresh, after this screen's next one)."""
        self.call_after_refresh(self.call_after_refresh, self._focused_in_view)

    def on_descendant_focus(self, event) -> None:
        """A list taking the focus (the screen's first, Tab) is scrolled into view; the
        device table laid out again when it takes or leaves the focus (``_show``)."""
        doctor = self.query_one("#device-table", DataTable)
        if self.doctor_rows and doctor.has_focus != self._doctor_whole:
            self._show(self.doctor_rows[:-1])
        self._keep_focused_in_view()

    def _focused_in_view(self) -> None:
        """The table with the focus stays in view when the lines above it grow (a
        pick's outcome, the saved-settings path): the row picked is where it is seen."""
        focused = self.app.focused
        if isinstance(focused, DataTable) and self in focused.ancestors:
            self.scroll_to_widget(focused, animate=False)

    def _say(self, text: str, error: bool = False) -> None:
        from_thread(self.app, self._show_result, text, error)
