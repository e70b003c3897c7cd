"""Signals: design a signal as a one-line expression, see its waveform and spectrum, save
it to the profile's library, audition it on patches or the screen through the gate."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from rich.text import Text
from textual.actions import SkipAction
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import Input, Label, OptionList, Static
from textual.widgets.option_list import Option

from console.config.signal_library import (
    BUILTIN,
    Entry,
    add_signal,
    check_name,
    check_target,
    library_data,
    library_path,
    read_library,
    remove_signal,
    restore_signal,
)
from console.core.errors import UserError
from console.safety import Limits
from console.session.events import ESTOP_FIX, Failed, PlayOutcome, Started
from console.signals.design import Summary, Target, parse_target, render, spectrum, summarize
from console.signals.expr import parse
from console.tui.charts import Chart, Series
from console.tui.focus_keys import name_field
from console.tui.kept_text import KeptText
from console.tui.lapse import lapse, lapse_if_held
from console.tui.list_keys import KeyedList
from console.tui.question_hold import answered, waits_for_question
from console.tui.said import status_said
from console.tui.util import from_thread
from console.tui.workers import work

DEFAULT_EXPR = BUILTIN["tone-250"].expr
#: the spectrum shows this many dB below its peak
SPECTRUM_RANGE_DB = 80.0
#: seconds in which a second enter loads a library signal over an unsaved expression
LOAD_AGAIN_S = 4.0


def wave_title(plotted: Target | None, typed: str) -> str:
    """The waveform's title: the target the plot shows, and when the target field says
    another (typed since, not plotted yet) that Enter plots it there; none plotted:
    no target."""
    if plotted is None:
        return "waveform"
    try:
        same = parse_target(typed) == plotted
    except UserError:
        same = False
    shown = "screen" if plotted.screen else plotted.label
    return f"waveform on {shown}" if same else f"waveform on {shown} (enter: {typed.strip()})"


def name_refusal(name: str) -> str:
    """Why ctrl+o refuses the name field's ``name`` ("" when empty, a built-in's or a
    name ctrl+s would take): it is what the line calls the play."""
    if not name or name in BUILTIN:
        return ""
    try:
        check_name(name)
    except UserError as exc:
        return f"{exc}; ctrl+o plays the top line's signal once the name is one or empty"
    return ""


def _named(field: Input, name: str) -> Input:
    """A field named in the footer: Enter plots (``on_input_submitted``), Esc leaves for
    the library (``action_leave_field``)."""
    return name_field(field, name, enter="plot", escape="leave")


@dataclass(frozen=True)
class Preview:
    expr: str
    target: Target
    fs: int
    volts: np.ndarray
    summary: Summary


class _Library(KeyedList):
    """The signal library's list: Tab goes back to the field Esc left (``SignalsPane``)."""

    BINDINGS = [Binding("tab", "back_to_field", "back to the field", show=False)]

    def action_back_to_field(self) -> None:
        pane = next(a for a in self.ancestors if isinstance(a, SignalsPane))
        pane.action_back_to_field()


class SignalsPane(Vertical):
    # one line per entry or paragraph: the help screen wraps it (console/tui/help.py)
    HELP_TEXT = (
        "Type a signal on the top line, a name and where it plays (PA, PA,PC, PALL, "
        "screen).\n"
        "enter    show its waveform and spectrum (before anything plays)\n"
        "escape   leave a field for the library (what was typed stays; Tab goes back)\n"
        "ctrl+o   play it through the safety gate (ctrl+e e-stops as everywhere)\n"
        "ctrl+s   save it under its name in the profile's library (twice replaces)\n"
        "ctrl+t   multiply it by the gate's minimum ramp (you see it in the expression)\n"
        "ctrl+z   in a field: undo its last change; in the library: bring back the signal "
        "just removed\n"
        "library  enter loads a signal; delete asks, delete again removes a saved one "
        "(built-ins, dimmed, are read-only)\n"
        "Syntax: sine|square|saw|triangle(250 Hz, 20 V, 1 s), chirp|logchirp(10 Hz, 600 Hz, "
        "10 V, 2 s), noise(5 V, 1 s, seed=1), silence(0.2 s); envelopes adsr(10 ms, 50 ms, "
        "0.7, 100 ms), ramp(10 ms), linramp(0, 1), expramp(1 %, 100 %); a + b, a * b, "
        "seq(a, b), a * 3 (repeat), a * 50 % or a * -6 dB (gain), lowpass(a, 2 kHz) (smooth "
        "edges).\n"
        "Volts at the actuator; the gate needs a ramp at both ends (ctrl+t) and steps within "
        "the slew limit (lowpass)."
    )
    DEFAULT_CSS = """
    SignalsPane { height: 1fr; }
    #sig-row { height: 1; }
    #sig-row .hint { width: 1fr; }
    #sig-name { width: 18; }
    #sig-target { width: 14; }
    #sig-status { height: auto; }  /* a refusal wraps: whole at 80 columns */
    #sig-status.error { color: $error; }
    #sig-main { height: 1fr; }
    #sig-library { width: 20; height: 1fr; border: none; padding: 0; }
    """
    BINDINGS = [
        Binding("ctrl+o", "play", "play"),
        # one of the two shows: "save" while the fields differ from the library, "saved"
        # once they are in it as they are (``check_action``); ctrl+s saves either way
        Binding("ctrl+s", "save", "save"),
        Binding("ctrl+s", "save_saved", "saved"),
        Binding("ctrl+t", "add_ramp", "add ramp"),
        Binding("ctrl+z", "undo", "undo", show=False),
        Binding("escape", "leave_field", "leave field", show=False),  # the hint says it
    ]

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.preview: Preview | None = None
        self._replace: str | None = None  # a name ctrl+s was pressed on once already
        self._delete: str | None = None  # a name delete was pressed on once already
        self._removed: tuple[str, dict] | None = None  # the last removed: ctrl+z restores
        self._playing = ""
        self._estop_said = False  # the status line says what an e-stop did or refused
        self._gen = 0
        self.entries: dict[str, Entry] = {}
        self._saved_shown = False  # the save key's label says "saved"
        self._status_line = ""  # what the status line says now
        self._refusal: str | None = None  # why the last preview failed (plots empty)
        self._load: str | None = None  # a signal enter asked to load over unsaved work
        #: (expr, name, target) a load replaced: ctrl+z brings them back
        self._overwritten: tuple[str, str, str] | None = None
        self._loaded_note = ""  # what the next preview's line says first ("loaded ...")
        self._left: Input | None = None  # the field Esc left for the library: Tab's

    def compose(self) -> ComposeResult:
        # each field named first in the footer while it has the focus (a new operator
        # typed " * 2" into the target, taking it for the expression)
        yield _named(
            Input(
                DEFAULT_EXPR,
                placeholder="sine(250 Hz, 20 V, 1 s) * ramp(10 ms)",
                id="sig-expr",
                compact=True,
                select_on_focus=False,  # typed work: the focus keeps it, a key types into it
            ),
            "expression",
        )
        with Horizontal(id="sig-row"):
            yield Label("name ")
            yield _named(
                Input(
                    "", placeholder="(to save)", id="sig-name", compact=True, select_on_focus=False
                ),
                "name",
            )
            yield Label(" on ")
            yield _named(
                Input(
                    "PA",
                    placeholder="PA,PC|screen",
                    id="sig-target",
                    compact=True,
                    select_on_focus=False,
                ),
                "target",
            )
            yield Static(self._hint(), classes="hint", id="sig-hint")
        yield KeptText("", id="sig-status", markup=False)  # "0.5 s" never split
        with Horizontal(id="sig-main"):
            # enter and delete in the footer while the library has the focus
            yield _Library(
                keys={"enter": "load", "delete": "remove"},
                on_delete=self._delete_pressed,
                id="sig-library",
            )
            yield Chart(
                title="waveform", x_label="time", x_unit="s", y_label="", y_unit="V", id="sig-wave"
            )
            yield Chart(
                title="spectrum",
                x_label="f",
                x_unit="Hz",
                y_label="",
                y_unit="V",
                log_x=True,
                db_y=True,
                id="sig-spectrum",
            )

    @property
    def focus_target(self):
        return self.query_one("#sig-expr", Input)

    def on_mount(self) -> None:
        self.reload_library()
        self.show_preview()

    def set_visible(self, visible: bool) -> None:
        """Shown again: the library may have changed (``haptable signals add``)."""
        if visible and self.is_mounted and self.query("#sig-library"):
            self.reload_library()

    # ------------------------------------------------------------------ helpers
    @waits_for_question
    def status(self, text: str, error: bool = False) -> None:
        line = " ".join(str(text).split())
        self._estop_said = error and ("e-stop" in line)  # a reset replaces it
        w = self.query_one("#sig-status", Static)
        w.update(Text(line))  # literal: "[limits]" in a message is no markup
        w.set_class(error, "error")
        self._status_line = line
        # in the log too; an error as a toast when this screen is not in view
        status_said(w, "Signals", line, "error" if error else "information")
        if error:  # a refusal because a run holds the outputs goes when the hold ends
            lapse_if_held(self, self.app.session, lambda: self._status_line, line, self.status)
        if self.preview is None:
            self._show_no_signal()

    def _show_wave_title(self) -> None:
        plotted = self.preview.target if self.preview is not None else None
        wave = self.query_one("#sig-wave", Chart)
        title = wave_title(plotted, self._fields()[2])
        if title != wave.title:
            wave.title = title
            wave.refresh()

    def _show_no_signal(self) -> None:
        """The empty plots point at the line above only while it says why they are
        empty (the preview's refusal); once another message took it, they say how to
        plot again."""
        said = self._refusal is not None and self._status_line == self._refusal
        text = "no signal: see the line above" if said else "no signal: enter plots it"
        for cid in ("#sig-wave", "#sig-spectrum"):
            self.query_one(cid, Chart).clear(text)
        self._show_wave_title()  # no plot: no target claimed

    @property
    def library_file(self):
        return library_path(self.app.ctx.profile.name)

    def reload_library(self, select: str | None = None) -> None:
        """The library list again (keeps the highlighted entry unless ``select``)."""
        ol = self.query_one("#sig-library", OptionList)
        if select is None and ol.highlighted is not None and ol.option_count:
            select = ol.get_option_at_index(ol.highlighted).id
        try:
            lib = read_library(self.library_file)
        except UserError as exc:
            self.entries = dict(BUILTIN)
            self.status(str(exc), error=True)
        else:  # an entry that does not validate is named; the others are listed
            self.entries = lib.entries
            if lib.problems:
                self.status(next(iter(lib.problems.values())), error=True)
        ol.clear_options()
        ol.add_options(  # built-ins dimmed (read-only); Text: names are never markup
            Option(Text(e.name, style="dim" if e.builtin else ""), id=e.name)
            for e in self.entries.values()
        )
        if select in self.entries:
            ol.highlighted = list(self.entries).index(select)
        self._show_saved()  # removed, replaced or saved elsewhere: the label follows

    def _fields(self) -> tuple[str, str, str]:
        return (
            self.query_one("#sig-expr", Input).value.strip(),
            self.query_one("#sig-name", Input).value.strip(),
            self.query_one("#sig-target", Input).value.strip(),
        )

    # ------------------------------------------------------------------ preview
    def on_input_submitted(self, event: Input.Submitted) -> None:
        event.stop()
        self.show_preview()

    def on_input_changed(self, event: Input.Changed) -> None:
        if event.input.id == "sig-name":
            self._replace = None
        if event.input.id == "sig-target":
            self._show_wave_title()
        self._show_saved()

    def saved_now(self) -> bool:
        """Whether the name and the expression are in the library as they are (saved,
        not a built-in): the footer and the hint say ``saved``, else ``save``."""
        if not self.is_mounted or not self.query("#sig-name"):
            return False
        expr, name, target = self._fields()
        entry = self.entries.get(name)
        return entry is not None and not entry.builtin and self._as_in(entry, expr, target)

    @staticmethod
    def _as_in(entry: Entry, expr: str, target: str) -> bool:
        """Whether ``expr`` on ``target`` is the library signal ``entry`` as it is (its
        declared channel too: a changed target is an edit, as a changed expression)."""
        if entry.expr.strip() != expr.strip():
            return False
        if not entry.target:
            return True
        try:
            return parse_target(target) == parse_target(entry.target)
        except UserError:
            return False

    def _hint(self, saved: bool = False) -> str:
        # Esc said where the operator types (a new one did not know how to leave the
        # field); ? help is in the footer
        return f" enter plot ^o play ^s {'saved' if saved else 'save'}  esc leave"

    def action_leave_field(self) -> None:
        """Esc in a field: the library takes the focus (the screen's keys, ``q`` too);
        what was typed stays; Tab from the library goes back to it."""
        if isinstance(self.app.focused, Input):
            self._left = self.app.focused
            self.query_one("#sig-library", KeyedList).focus()

    def action_back_to_field(self) -> None:
        """Tab in the library after Esc left a field: that field again (README: "Tab
        goes back"); else Tab moves on as it always does."""
        left, self._left = self._left, None
        if left is None or not left.is_mounted:
            raise SkipAction()
        left.focus()

    def _show_saved(self) -> None:
        """The save key's label as it is true now (a change makes it ``save`` again)."""
        saved = self.saved_now()
        if saved != self._saved_shown:
            self._saved_shown = saved
            self.query_one("#sig-hint", Static).update(self._hint(saved))
            self.refresh_bindings()

    def check_action(self, action: str, parameters: tuple) -> bool | None:
        """Of ctrl+s's two labels, the one that is true shows (and runs)."""
        if action in ("save", "save_saved"):
            return (action == "save_saved") == self.saved_now()
        return True

    def action_save_saved(self) -> None:
        self.action_save()

    def show_preview(self, then_play: bool = False) -> None:
        """Parse and render the fields' signal (off the UI thread), then plot it; with
        ``then_play`` it plays once the plots show."""
        self._gen += 1  # a slower earlier preview never overwrites this one
        self._compute_preview(self._gen, *self._fields(), then_play)

    @work(thread=True, exclusive=True, group="sig-preview")
    def _compute_preview(
        self, gen: int, expr: str, name: str, target_text: str, then_play: bool
    ) -> None:
        prof = self.app.ctx.profile
        try:
            target = parse_target(target_text)
            fs = int(prof.get("audio.sample_rate_hz"))
            node = parse(expr, data=library_data(self.library_file))  # @NAME: imported data
            x = render(node, fs, max_s=float(prof.get("limits.max_plan_s")))
        except UserError as exc:
            from_thread(self.app, self._refused, gen, str(exc))
            return
        p = Preview(expr, target, fs, x, summarize(x, fs))
        label = self.play_label(expr, name, target_text) if then_play else None
        from_thread(self.app, self._show, gen, p, label)

    def _refused(self, gen: int, message: str) -> None:
        if gen != self._gen:
            return
        self.preview = None
        self._loaded_note = ""
        self._refusal = " ".join(message.split())
        self.status(message, error=True)

    def _show(self, gen: int, p: Preview, play_name: str | None) -> None:
        if gen != self._gen:
            return
        self.preview = p
        t = np.arange(p.volts.size) / p.fs
        channel = "screen" if p.target.screen else p.target.label
        wave = self.query_one("#sig-wave", Chart)
        wave.y_label = "screen" if p.target.screen else "piezo"
        wave.set_series(
            [Series(channel, t, p.volts)], title=wave_title(p.target, self._fields()[2])
        )
        # the designed signal is finite and whole: no window, so a chirp's ends keep
        # their level (a Hann window would draw it as a bump)
        f, mag = spectrum(p.volts, p.fs, window=False)
        spec = self.query_one("#sig-spectrum", Chart)
        top = 20 * np.log10(max(float(mag.max(initial=0.0)), 1e-9))
        spec.db_floor = top - SPECTRUM_RANGE_DB
        keep = f >= 1.0  # a log axis: from 1 Hz
        spec.set_series([Series("|X|", f[keep], mag[keep])])
        note, self._loaded_note = self._loaded_note, ""  # the fields: loaded or back
        self.status(f"{note}: {p.summary.line()}" if note else p.summary.line())
        if play_name is not None:
            self._audition(p, play_name or "designed")

    def play_label(self, expr: str, name: str, target: str = "") -> str:
        """What a play of ``expr`` on ``target`` is called: the name field's signal when
        they are its saved expression and declared channel, else the designed signal (the
        name a save would give it)."""
        entry = self.entries.get(name)
        if entry is not None and self._as_in(entry, expr, target):
            return name
        return f"designed ({name} edited)" if entry is not None else name or "designed"

    # ------------------------------------------------------------------ play, save, load
    def action_play(self) -> None:
        """ctrl+o plays the top line's signal; a name field that holds no name (a signal
        typed there) is refused as ctrl+s refuses it: the line never names what does not
        play."""
        why = name_refusal(self._fields()[1]) or self.app.session.held_why()
        if why:  # a demo or a run holding the outputs: said before the signal is drawn
            self._playing = ""
            self.status(why, error=True)
            return
        self.show_preview(then_play=True)

    def _audition(self, p: Preview, name: str) -> None:
        """The line says "playing" only once the outputs report the start: first the
        gate's checks (as ``haptable signals play --dry-run``), then the play."""
        self._playing = name
        self.status(f"checking {name} on {p.target.label} against the limits ...")
        self._play(p, name)

    @work(thread=True, group="sig-play")
    def _play(self, p: Preview, name: str) -> None:
        """Check the signal against the limits, play it through the gate and say what
        became of it (``ConsoleSession.play``): once, on this screen's status line."""
        from console.session.audition import audition_plan  # lazy: SciPy on first play

        try:
            node = parse(p.expr, data=library_data(self.library_file))
            plan = audition_plan(self.app.ctx.profile, node, p.target, name)
        except UserError as exc:
            from_thread(self.app, self._refused_play, name, str(exc))
            return
        from_thread(self.app, self._checked, p, name, "starting")
        outcome = self.app.session.play(
            plan, on_started=lambda: from_thread(self.app, self._checked, p, name, "playing")
        )
        from_thread(self.app, self._played, p, outcome)

    def _checked(self, p: Preview, name: str, state: str) -> None:
        """``starting`` (the checks passed) or ``playing`` (the outputs started it)."""
        if self._playing == name:
            self.status(f"{state} {name} on {p.target.label}: {p.summary.line()}")

    def _refused_play(self, name: str, message: str) -> None:
        if self._playing == name:
            self._playing = ""
            hint = " (ctrl+t adds it)" if "ramp_min_ms" in message else ""
            self.status(message + hint, error=True)

    def _played(self, p: Preview, outcome: PlayOutcome) -> None:
        """The status line says how the play it announced ended (unless another play
        took the line meanwhile)."""
        name = outcome.name
        if self._playing != name:
            return
        self._playing = ""
        if outcome.played:
            self.status(f"played {name} on {p.target.label} ({p.summary.duration_s:.2f} s)")
        elif outcome.refused:
            self.status(f"{name} {outcome.refused}", error=True)
        elif outcome.stopped.startswith("the e-stop"):
            why = outcome.stopped.removeprefix("the e-stop").strip()
            self.status(
                f"{name} stopped by the e-stop{' ' + why if why else ''}; {ESTOP_FIX}, "
                "then ctrl+o plays",
                error=True,
            )
        else:
            self.status(f"{name} {outcome.how_it_stopped}", error=True)

    def says(self, ev) -> bool:
        """A refusal of this screen's play: its status line says it (``_played``), no
        toast (``console.tui.said``)."""
        return isinstance(ev, Failed) and ev.topic in ("signals", "outputs") and bool(self._playing)

    def on_session_message(self, message) -> None:
        """The e-stop's reset clears what the e-stop stopped or refused here (the play's
        own end is said by ``_played``, once)."""
        ev = message.event
        if isinstance(ev, Started) and ev.topic == "estop" and self._estop_said:
            self.status("e-stop reset: ctrl+o plays")  # what the e-stop refused is past

    def action_add_ramp(self) -> None:
        """The designer adds the gate's minimum ramp to the expression, in plain sight."""
        ms = float(self.app.ctx.profile.get("limits.ramp_min_ms"))
        box = self.query_one("#sig-expr", Input)
        expr = box.value.strip()
        if not expr:
            return
        box.value = f"({expr}) * ramp({ms:g} ms)"
        box.cursor_position = len(box.value)  # typing goes on after it, not inside it
        self.show_preview()

    def action_save(self) -> None:
        expr, name, target = self._fields()
        lib = self.entries
        replace = self._replace == name
        if (
            name in lib
            and not lib[name].builtin
            and not self._as_in(lib[name], expr, target)
            and not replace
        ):
            self._replace = name
            self.status(f"{name} is already saved: ctrl+s again replaces it", error=True)
            return
        try:  # saved with the channel the target field names (loading it sets it back),
            # checked as ctrl+o and the CLI check it: a target naming none is refused
            meant = check_target(target)
            limits = Limits.from_profile(self.app.ctx.profile)
            add_signal(self.library_file, name, expr, replace=True, limits=limits, target=meant)
        except UserError as exc:
            self.status(str(exc), error=True)
            return
        self._replace = None
        self.reload_library(select=name)
        where = f"for {meant}" if meant else "for any channel"
        self.status(f"saved {name} {where} in {self.library_file}")
        self._show_saved()
        # the saved signal is plotted (the plots said "no signal" since an error), where
        # the target field says; an empty field plots nowhere and keeps the saved line
        if not meant:
            return
        self._loaded_note = f"saved {name} {where} in {self.library_file}"
        self.show_preview()

    def unsaved(self) -> bool:
        """The expression field holds typed work the library does not have (not the
        default, nor any library signal's expression)."""
        expr, _name, _target = self._fields()
        known = {e.expr.strip() for e in self.entries.values()}
        return bool(expr) and expr != DEFAULT_EXPR.strip() and expr not in known

    def unsaved_work(self) -> str:
        """What quitting would lose (``console.tui.long_work.KeepsTypedWork``)."""
        return "your signal (ctrl+s on Signals saves it)" if self.unsaved() else ""

    def on_option_list_option_selected(self, event: OptionList.OptionSelected) -> None:
        """Enter on a library signal loads it into the fields; over an unsaved
        expression it asks first (enter again within ``LOAD_AGAIN_S``), and ctrl+z
        brings the expression back."""
        e = self.entries.get(event.option.id or "")
        if e is None:
            return
        answered(self)  # Enter again answers its question; another asks anew
        asked, self._load = self._load, None
        over = self.unsaved() and self._fields()[0] != e.expr.strip()
        if over and asked != e.name:
            self._load = e.name
            text = (
                f"enter again within {LOAD_AGAIN_S:g} s loads {e.name} over your unsaved "
                "expression (ctrl+z then brings it back)"
            )
            self.status(text)  # the question holds the line until it lapses
            then = "your unsaved expression stays in the fields: ctrl+s saves it"
            lapse(self, lambda: self._status_line, text, self._load_lapsed, LOAD_AGAIN_S, then=then)
            return
        if over:
            self._overwritten = self._fields()
            self._removed = None  # ctrl+z brings back the most recent: the expression
        self._loaded_note = (
            f"loaded {e.name}"
            + (f" on {e.target} (the channel it is meant for)" if e.target else "")
            + (" over your expression (ctrl+z brings it back)" if over else "")
        )
        fields = [("#sig-expr", e.expr), ("#sig-name", e.name)]
        if e.target:  # the channel it is meant for: the field shows where it plays
            fields.append(("#sig-target", e.target))
        for wid, text in fields:
            box = self.query_one(wid, Input)
            box.value, box.cursor_position = text, len(text)
        self._replace = None
        self.show_preview()

    @waits_for_question
    def _load_lapsed(self, then: str) -> None:
        self._load = None
        self.status(then)

    def on_option_list_option_highlighted(self, event: OptionList.OptionHighlighted) -> None:
        if self._delete is not None and event.option.id != self._delete:
            self._keep_asked()  # a delete asked for another signal: it lapses

    def on_key(self, event) -> None:
        if event.key != "delete" and self._delete is not None:
            self._keep_asked()  # any other key: the question lapses

    def _keep_asked(self) -> None:
        """The delete question lapses: the status line says the signal stays (it asked)."""
        name, self._delete = self._delete, None
        if self._status_line.startswith("delete again to remove"):
            self.status(f"{name} kept (delete twice removes it)")

    def _delete_pressed(self, name: str) -> None:
        """Delete on a library entry: the first press asks, a second on the same entry
        removes it (ctrl+z brings it back); a built-in is read-only."""
        entry = self.entries.get(name)
        if self._delete != name and (entry is None or not entry.builtin):
            self._delete = name
            self.status(f"delete again to remove {name!r} (any other key keeps it)")
            return
        self._delete = None
        try:
            raw = remove_signal(self.library_file, name)
        except UserError as exc:
            self.status(str(exc), error=True)
            return
        self._removed, self._overwritten = (name, raw), None
        self.reload_library()
        self.status(f"removed {name} from the library (ctrl+z brings it back)")

    def action_undo(self) -> None:
        """ctrl+z: a text field's last change (``console.tui.typed``), else the signal
        just removed, back in the library as it was."""
        if isinstance(self.app.focused, Input):
            self.app.action_undo()
            return
        if self._overwritten is not None:  # the expression a load replaced
            fields, self._overwritten = self._overwritten, None
            for wid, text in zip(("#sig-expr", "#sig-name", "#sig-target"), fields, strict=True):
                box = self.query_one(wid, Input)
                box.value, box.cursor_position = text, len(text)
            self._loaded_note = "your expression is back"
            self.show_preview()
            return
        if self._removed is None:
            return
        name, raw = self._removed
        try:
            restore_signal(self.library_file, name, raw)
        except UserError as exc:
            self.status(str(exc), error=True)
            return
        self._removed = None
        self.reload_library(select=name)
        self.status(f"{name} is back in the library")
