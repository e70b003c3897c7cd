"""The electrostatic plugin's screen (F5, Electrostatic): audition the knob conditions and
friction presets; amplitude and frequency controls kept inside the limits, with the
expected force of the setting.

Everything goes through effect capabilities (``console.core.contracts``): the ``Conditions``
effect's conditions and the ``Presets`` effect's presets fill the list; the setting is
rendered by the ``Presets`` effect."""

from __future__ import annotations

from typing import Any

import numpy as np
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Horizontal, Vertical
from textual.widgets import OptionList, Static
from textual.widgets.option_list import Option

from console.plugin_api import Conditions, Limits, Presets, UserError
from console.plugin_api.runtime import Started
from console.plugin_api.tui import (
    KeptText,
    SessionMessage,
    escape,
    from_thread,
    lapse_if_held,
    show_keys,
    status_said,
    work,
)

from .effects import slew_max_vpp

#: an e-stop's fix, as the console's lines say it (``console.session.events.ESTOP_FIX``)
ESTOP_FIX = "ctrl+r resets"

FREQ_RANGE_HZ = (10.0, 1000.0)
SLEW_WHERE = (
    "(the screen's slew limit: [amplifiers] screen_peak_current_ma, [screen] capacitance_nf)"
)


def clamp_setting(vpp: float, freq_hz: float, max_vpp: float) -> tuple[float, float]:
    """Keep a setting inside the limits: 0 <= vpp <= max_vpp, freq within FREQ_RANGE_HZ."""
    return (
        float(min(max(vpp, 0.0), max_vpp)),
        float(min(max(freq_hz, FREQ_RANGE_HZ[0]), FREQ_RANGE_HZ[1])),
    )


def limit_line(vpp: float, freq_hz: float, max_vpp: float, max_from: str) -> str:
    """Why a setting asked for (``vpp``, ``freq_hz``) stays where it is: the limit it
    would pass, and where that limit is set (``max_from``, for the maximum Vpp)."""
    lo, hi = FREQ_RANGE_HZ
    if vpp > max_vpp:
        return f"{max_vpp:g} Vpp is the screen's maximum ({max_from})"
    if vpp < 0:
        return "0 Vpp is the minimum: + raises it"
    if freq_hz > hi:
        return f"{hi:g} Hz is the maximum ({lo:g}-{hi:g} Hz): [ lowers it"
    return f"{lo:g} Hz is the minimum ({lo:g}-{hi:g} Hz): ] raises it"


def force_text(meta: dict) -> str:
    """The expected force of a stimulus (effect meta) in words."""
    felt = (
        "[red]below the detection threshold[/]"
        if meta.get("below")
        else f"[green]{meta.get('margin_db', 0):+.1f} dB above threshold[/]"
    )
    return (
        f"expected attraction {meta['force_mean_n'] * 1e3:.1f} mN mean, "
        f"{meta['force_peak_n'] * 1e3:.1f} mN peak; friction change "
        f"{meta['friction_change_mean_n'] * 1e3:.1f} mN on {meta['friction_base_n']:.2f} N; "
        f"threshold {meta['threshold_vpp']:.0f} Vpp: {felt}"
    )


class ElectrostaticPane(Vertical):
    HELP_TEXT = (
        "enter    audition the highlighted knob condition or friction preset\n"
        "+ / -    amplitude (Vpp, held inside [limits] screen_max_vpp)\n"
        "[ / ]    frequency (10-1000 Hz)   t  sine/square   p  play the setting (1 s)"
    )
    # the footer shows every key at 80 columns, the list's Enter first, then p (the main
    # action), each pair of keys (+ -, [ ]) as one entry
    BINDINGS = [
        Binding("p", "play_custom", "play"),
        Binding("t", "waveform", "sine/square"),
        Binding("plus,equals_sign", "vpp(10)", "+10 Vpp", show=False),
        Binding("minus", "vpp(-10)", "Vpp", key_display="+ -"),  # 10 Vpp a step
        Binding("right_square_bracket", "freq(10)", "+10 Hz", show=False),
        Binding("left_square_bracket", "freq(-10)", "Hz", key_display="[ ]"),  # 10 Hz a step
    ]

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.vpp, self.freq_hz, self.waveform = 100.0, 180.0, "sine"
        self.max_vpp = 200.0
        self.max_from = "[limits] screen_max_vpp"  # where max_vpp is set
        self._at_limit = False  # the line says a key met a limit (stale once one moves)
        self.conditions: tuple[str, ...] = ()
        self.presets: dict[str, dict] = {}
        self.notes: list[str] = []
        self.status_text = ""  # the status line: what became of the last play asked for
        self._asked = None  # the plan the status line is about (a newer one takes it)
        self._estop_refused = False  # the line says what the e-stop did (refused, stopped)

    def _offering(self, capability: type) -> Any:
        """The effect offering ``capability`` (``Conditions``, ``Presets``), or None."""
        ctx = self.app.ctx
        found = ctx.pm.providers("effect", capability, ctx.profile)
        return found[0][1] if found else None

    def _effect(self, capability: type) -> Any:
        ctx = self.app.ctx
        return ctx.pm.provider("effect", capability, ctx.profile, plugin_hint="electrostatic")

    def compose(self) -> ComposeResult:
        if self._offering(Presets) is None and self._offering(Conditions) is None:
            yield Static(
                "no electrostatic effects: the electrostatic plugin is not installed or is "
                "blocked (HAPTABLE_BLOCK_PLUGINS)"
            )
            return
        with Horizontal(id="es-top"):
            yield show_keys(OptionList(id="es-list"), enter="audition")  # first in the footer
            yield Static(id="es-setting")
        yield KeptText(  # a key and its word on one line, whatever the width
            "enter: audition the highlighted item   + -: amplitude   [ ]: frequency   "
            "t: waveform   p: play the setting",
            markup=False,
            classes="hint",
            id="es-keys",
        )
        yield Static("", id="es-status", markup=False)

    @property
    def focus_target(self):
        lst = self.query("#es-list")
        return lst.first() if lst else None

    def on_mount(self) -> None:
        if not self.query("#es-list"):
            return
        limits = Limits.from_profile(self.app.ctx.profile)
        lo, hi = limits.screen_range()
        self.max_vpp = hi - lo
        if limits.screen_card_v < limits.screen_max_v:  # the card, not the limit, caps it
            self.max_from = "the sound card's range times [amplifiers] screen_gain"
        lst = self.query_one("#es-list", OptionList)
        notes = []
        knob, screen = self._offering(Conditions), self._offering(Presets)
        if knob is not None:
            self.conditions = tuple(knob.conditions)
            for c in self.conditions:
                lst.add_option(Option(f"knob {c}", id=f"cond:{c}"))
        if not self.conditions:
            notes.append("no effect plugin offers knob conditions: install/enable electrostatic")
        if screen is not None:
            presets = screen.presets or {}
            self.presets = {str(k): dict(v) for k, v in presets.items()}
            for name, p in self.presets.items():
                lst.add_option(
                    Option(
                        f"{name}: {p['vpp']:g} Vpp {p['freq_hz']:g} Hz {p.get('waveform', 'sine')}",
                        id=f"preset:{name}",
                    )
                )
        if not self.presets:
            notes.append("no effect plugin offers friction presets: install/enable electrostatic")
        if lst.option_count:
            lst.highlighted = 0
        self.notes = notes
        if screen is not None:
            self._update_setting()
        else:
            self._show_setting(
                "[yellow]no effect plugin offers an electrostatic stimulus: install/enable "
                "electrostatic[/]"
            )

    # ------------------------------------------------------------------ setting
    def action_vpp(self, step: float) -> None:
        self._change(self.vpp + step, self.freq_hz)

    def action_freq(self, step: float) -> None:
        self._change(self.vpp, self.freq_hz + step)

    def _change(self, vpp: float, freq_hz: float) -> None:
        """The setting moved toward (``vpp``, ``freq_hz``) inside the limits (the
        screen's maximum, the frequency range, the slew limit for the waveform); a key
        that cannot move it says which limit stops it on the status line."""
        new = clamp_setting(vpp, freq_hz, self.max_vpp)
        why = limit_line(vpp, freq_hz, self.max_vpp, self.max_from)
        cap = self._slew_cap(new[1], self.waveform)
        if new[0] > cap:  # over the slew limit: the amplitude stops at it, a frequency stays
            if new[1] != self.freq_hz:
                new, why = (self.vpp, self.freq_hz), self._slew_line(new[1], cap, raising="freq")
            else:
                new, why = (
                    (min(self.vpp, float(np.floor(cap))), new[1]),
                    self._slew_line(new[1], cap, raising="vpp"),
                )
        if new == (self.vpp, self.freq_hz):
            self.say(why)
            self._at_limit = True
            return
        if self._at_limit:  # that limit no longer stops anything
            self.say("")
        self.vpp, self.freq_hz = new
        self._update_setting()

    def _slew_cap(self, freq_hz: float, waveform: str) -> float:
        """The largest Vpp the screen's slew limit lets ``waveform`` at ``freq_hz`` play
        (inf where the profile does not say: the play's own check then answers)."""
        try:
            return slew_max_vpp(self.app.ctx.profile, freq_hz, waveform)
        except (UserError, KeyError, ValueError):
            return float("inf")

    def _slew_line(self, freq_hz: float, cap: float, raising: str) -> str:
        """Why the slew limit stops a key, with the key that makes room."""
        head = f"{np.floor(cap):g} Vpp is the most a {self.waveform} at {freq_hz:g} Hz may have"
        if raising == "freq":
            fix = "- lowers the amplitude first"
        elif self.waveform == "square":
            fix = "t: a sine is gentler"
        else:
            fix = "[ lowers the frequency"
        return f"{head} {SLEW_WHERE}: {fix}"

    def action_waveform(self) -> None:
        self.waveform = "square" if self.waveform == "sine" else "sine"
        cap = self._slew_cap(self.freq_hz, self.waveform)
        if self.vpp > cap:  # the square's edges: the amplitude comes down to the limit
            self.vpp = float(np.floor(cap))
            self.say(
                f"{self.waveform}: amplitude lowered to {self.vpp:g} Vpp, the most a "
                f"{self.waveform} at {self.freq_hz:g} Hz may have {SLEW_WHERE}"
            )
            self._at_limit = True
        elif self._at_limit:  # what the line said of the other waveform's limit is past
            self.say("")
        self._update_setting()

    @work(thread=True, exclusive=True, group="es-report")
    def _update_setting(self) -> None:
        try:
            plan = self._render_setting(0.1)
            text = force_text(plan.meta)
        except UserError as exc:
            text = f"[red]{escape(exc)}[/]"
        from_thread(self.app, self._show_setting, text)

    def _show_setting(self, text: str) -> None:
        notes = "".join(f"\n[yellow]{escape(n)}[/]" for n in self.notes)
        self.query_one("#es-setting", Static).update(
            f"[b]setting[/b] {self.vpp:g} Vpp (max {self.max_vpp:g} Vpp), {self.freq_hz:g} Hz, "
            f"{escape(self.waveform)}\n" + text + notes
        )

    def _render_setting(self, duration_s: float):
        return self._effect(Presets).render(
            vpp=self.vpp, freq_hz=self.freq_hz, duration_s=duration_s, waveform=self.waveform
        )

    # ------------------------------------------------------------------ audition
    def on_option_list_option_selected(self, event: OptionList.OptionSelected) -> None:
        event.stop()
        kind, name = event.option.id.split(":", 1)
        if kind == "preset":
            p = self.presets[name]
            self.vpp, self.freq_hz = clamp_setting(p["vpp"], p["freq_hz"], self.max_vpp)
            self.waveform = p.get("waveform", "sine")
            self.vpp = min(self.vpp, float(np.floor(self._slew_cap(self.freq_hz, self.waveform))))
            self._update_setting()
            self.action_play_custom()
        else:
            self._play_condition(name)

    def action_play_custom(self) -> None:
        self._play_setting()

    @work(thread=True, group="es-play")
    def _play_setting(self) -> None:
        try:
            plan = self._render_setting(1.0)
        except UserError as exc:
            from_thread(self.app, self.say, str(exc), True)
            return
        self._play(plan, f"{plan.segments[0].label} on the screen")

    @work(thread=True, group="es-play")
    def _play_condition(self, condition: str) -> None:
        try:
            plan = self._effect(Conditions).render(condition=condition)
        except UserError as exc:
            from_thread(self.app, self.say, str(exc), True)
            return
        silent = not any(
            np.any(seg.screen_v) or np.any(seg.piezo_v) for seg in plan.segments
        )  # a condition without haptic feedback (V: visual only)
        self._play(
            plan,
            f"knob {condition}: a canned rotation, {plan.duration_s:.1f} s, "
            f"{plan.meta.get('crossings', 0)} detents"
            + (": no haptic feedback in this condition, the outputs stay at 0 V" if silent else ""),
            again=f"enter plays knob {condition} again",
        )

    # ------------------------------------------------------------------ status
    def _play(self, plan, what: str, again: str = "p plays") -> None:
        """In a worker: ask the outputs to play ``plan``; the status line says asking,
        then playing when the outputs report its start, then what became of it
        (``ConsoleSession.play``), never ahead of it."""
        from_thread(self.app, self._asking, plan, what)
        outcome = self.app.session.play(
            plan, on_started=lambda: from_thread(self.app, self._about, plan, f"playing {what}")
        )
        if outcome.played:
            text, error = f"played {what}", False
        elif outcome.refused:
            text, error = f"{what}: {outcome.refused}", True
        else:
            text, error = f"{what}: {outcome.how_it_stopped}", True
        by_estop = outcome.estop_refused or outcome.stopped.startswith("the e-stop")
        if by_estop and "ctrl+r" not in text:  # the fix, as every e-stop line says it
            text += f"; {ESTOP_FIX}, then {again}"  # the key that plays it again
        from_thread(self.app, self._about, plan, text, error, by_estop)

    def _asking(self, plan, what: str) -> None:
        self._asked = plan
        self.say(f"asking to play {what} ...")

    def _about(self, plan, text: str, error: bool = False, by_estop: bool = False) -> None:
        """``text`` on the line if it is still about ``plan`` (no newer play took it)."""
        if plan is self._asked:
            self.say(text, error)
            self._estop_refused = by_estop

    def say(self, text: str, error: bool = False) -> None:
        """The status line (one line, the newest message replaces it)."""
        self.status_text = text
        self._estop_refused = self._at_limit = False
        found = self.query("#es-status")
        if found:
            found.first(Static).update(text)
            found.first(Static).set_class(error, "error")
            # in the log too; an error as a toast while the screen is not in view
            status_said(found.first(Static), "Electrostatic", text, "error" if error else "")
            # a refusal because a run holds the outputs leaves the line when the run ends
            lapse_if_held(self, self.app.session, lambda: self.status_text, text, self.say)
            # once the line has its new rows: it is laid out on the refresh after this one
            self.call_after_refresh(self.call_after_refresh, self._status_whole)

    #: the rows the list and the setting take at most (the list's border included)
    TOP_ROWS = 16
    #: ... and the list alone
    LIST_ROWS = 14

    def _status_whole(self) -> None:
        """The status line keeps its rows whole (a long e-stop reason ends with its fix,
        ``close other programs before resetting``): the list and the setting above it
        give way, down to 3 rows (the list scrolls within itself, its highlighted item
        in view), and take their rows back once the line is shorter."""
        found = self.query("#es-top")
        if not found:
            return
        below = sum(self.query_one(f"#es-{n}").outer_size.height for n in ("keys", "status"))
        rows = max(3, min(self.TOP_ROWS, self.size.height - below))
        found.first().styles.max_height = rows
        self.query_one("#es-list").styles.max_height = min(rows, self.LIST_ROWS)

    def on_resize(self, _event) -> None:
        self.call_after_refresh(self._status_whole)

    def on_session_message(self, message: SessionMessage) -> None:
        """A reset clears what the line said the e-stop did (a refusal, a stopped play)."""
        ev = message.event
        if isinstance(ev, Started) and ev.topic == "estop" and self._estop_refused:
            self._asked = None
            self.say("e-stop reset: p or enter plays")
