"""Devices: the profile, each device with its doctor status and fix, the sound card and
relay board to use (picked here, saved to the profile's override file, the outputs
reopened with them), a named test signal through the gate, and every plugin."""

from __future__ import annotations

import math
import time
from typing import Any

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical, VerticalScroll
from textual.widgets import DataTable, Static

from console.config.profile import overrides_path
from console.core.errors import UserError
from console.core.types import DeviceStatus
from console.runtime.devices import output_devices, relay_boards
from console.session.events import ESTOP_FIX, Started, Stopped
from console.signals.stimuli import STIMULI, make_stimulus
from console.tui.ask_again import AskAgain
from console.tui.choice import Choice, chosen
from console.tui.device_cells import (
    cell,
    note_room,
    note_width,
)
from console.tui.device_picks import DevicePicksMixin
from console.tui.focus_keys import name_field, show_keys
from console.tui.kept_text import KeptText
from console.tui.lapse import HELD_ENDED, lapse, lapse_if_held
from console.tui.panes.devices_doctor import DevicesDoctorMixin
from console.tui.panes.devices_plugins import fill_plugins
from console.tui.panes.devices_selftest import DevicesSelftestMixin
from console.tui.question_hold import waits_for_question
from console.tui.said import status_said
from console.tui.session_messages import SessionMessage
from console.tui.table_fit import NOTE_MIN, need, share, widths
from console.tui.text import LiteralTable
from console.tui.util import from_thread, short_path
from console.tui.workers import work

#: the sound-card table's device column at most (the note takes what the other columns
#: leave of the screen's width)
DEVICE_MAX = 23


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
#: seconds the reset's line stays: news of the reset, not a state (it went stale)
RESET_NEWS_S = 60.0


#: the test signal's heading: how one is chosen and what ``t`` does with it
TEST_SIGNAL_HEADING = "test signal (Tab here, enter lists them; t plays the chosen one)"


def _says_estop(line: str) -> bool:
    """Whether ``line`` says the e-stop is active (stale once the operator reset it)."""
    words = ("e-stop active", "e-stop is active", "e-stop latched", "ctrl+r resets")
    return any(w in line for w in words)


class DevicesPane(DevicesDoctorMixin, DevicesSelftestMixin, DevicePicksMixin, VerticalScroll):
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
        #: `haptable doctor`'s quick part's line when it skips now ("": it would run)
        self.quick_skips = ""
        self._selftest_timer = None  # the self-test's progress ticks while it runs
        #: the self-test's start (monotonic s), seconds expected and estimate, for ticks
        self._selftest_clock: tuple[float, float, Any] = (0.0, 0.0, None)
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
        yield name_field(
            show_keys(
                Choice(
                    [(f"{name}: {desc}", name) for name, (desc, _) in STIMULI.items()],
                    value="sine-PA",
                    id="stimulus",
                ),
                enter="test signals",
            ),
            "test signal",
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
        table = self.query_one("#plugin-table", DataTable)
        self.plugin_rows = fill_plugins(table, self.app.ctx.pm, self._table_width())

    def _table_width(self) -> int:
        """The width every table has: the screen's less its scrollbar's gutter (kept
        whether or not the lists overflow); the terminal's while the screen is hidden."""
        return self.scrollable_content_region.width or self.app.size.width - 2

    def on_resize(self, event) -> None:
        """The terminal's width changed (tmux resized, a window dragged): every table
        laid out again within it (a table wider than the screen scrolls sideways and
        cuts its first column)."""
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

        name = from_thread(self.app, lambda: chosen(self.query_one("#stimulus", Choice).value))
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
            why = outcome.refused or outcome.how_it_stopped
            if outcome.stopped.startswith("the e-stop"):  # its fix, as every e-stop line
                why += f"; {ESTOP_FIX}, then t plays"
            self._say(f"{name} on {where!r}: {why}", error=True)
            return
        trace = session.scope(plan.duration_s + 0.5)
        peaks = (
            ""
            if trace is None
            else ", ".join(f"{ch} {v:.1f} V peak" for ch, v in trace.peak_v().items())
        )
        self._say(f"{name} played on {where!r} through the gate: {peaks}")

    @waits_for_question(progress="tick")
    def _show_result(
        self, text: str, error: bool = False, severity: str = "", tick: bool = False
    ) -> None:
        """The screen's status line, the newest message replacing it: docked at the
        top of the screen, in view wherever the list is scrolled (a pick on a row far
        down says what it did where it is seen); an error or a refusal (``severity``
        ``warning``) is in the log too. While the self-test runs, a message that is not
        its ``tick`` holds the line ``NOTE_S`` against the ticks (``question_hold``)."""
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
        replaces a line saying the reset or that plays work again: it is latched again."""
        ev = message.event
        if ev.topic == "estop" and self.doctor_rows:  # a stopped run's row (this session's
            self._show(self.doctor_rows[:-1])  # or kept): ctrl+r first or not
        if isinstance(ev, Started) and ev.topic == "estop" and _says_estop(self.result):
            said = f"{RESET}: t plays the test signal, enter picks a row"
            self._show_result(said)
            # news of the reset: it leaves the line after a while (still true: it says so)
            lapse(
                self,
                lambda: self.result,
                said,
                self._show_result,
                RESET_NEWS_S,
                while_true=lambda: True,
            )
        elif (
            isinstance(ev, Stopped)
            and ev.topic == "estop"
            and (self.result.startswith(RESET) or self.result == HELD_ENDED)
            and self._estop_latched()  # a late echo of an e-stop reset since says nothing
        ):
            # latched again: the line saying the reset is no longer true
            why = " ".join(ev.reason.split())
            self._show_result(f"e-stop active{': ' + why if why else ''}; {ESTOP_FIX}", True)

    def _estop_latched(self) -> bool:
        """Whether the outputs' e-stop is latched now (not only when a message said so)."""
        out = self.app.session.outputs
        return out is None or bool(out.estopped)

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
