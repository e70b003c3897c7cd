"""Scope: what the safety gate handed the driver, per channel, in volts at the actuators
(what the amplifiers got), refreshed live; ``space`` freezes it, ``p`` shows the last
played plan whole, ``+``/``-`` change the time window. E-stops in view are marked with
the level they ramped down from and how long the ramp took."""

from __future__ import annotations

import numpy as np
from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.widgets import Static

from console.session.core import PLAN_MARGIN_S
from console.tui.charts import Chart, Series
from console.tui.kept_text import KeptText
from console.tui.scope_recording import SCOPE_REPLAY_BINDINGS, ScopeRecordingMixin

#: the time windows ``+``/``-`` step through, in ms
WINDOWS_MS = (5, 10, 20, 50, 100, 200, 500, 1000, 2000, 4000)
#: around the last plan (``p``): this much before and after it, in ms
PLAN_MARGIN_MS = PLAN_MARGIN_S * 1e3
#: how often the live view is read while the screen shows
TICK_S = 0.2


def plan_line(last) -> str:
    """The last plan the gate passed in words (a ``KernelPlan``): name, who sent it
    (when not this console), length, where it played, and whether done."""
    if last is None:
        return "no plan played yet"
    state = "playing" if not last.done else (last.error or "done")
    sender = "" if last.own else f" from {last.who}"
    return (
        f"last plan {last.name}{sender}: {last.duration_s:.2f} s on "
        f"{','.join(last.where) or 'nothing'} ({state})"
    )


def ramp_words(trace, clock: int) -> str:
    """How the outputs went silent from gate clock ``clock``: from the level of the
    sample before it to the first silent sample (at least one sample period, shown to
    a sample's precision: never "0.00 ms"); silent already: no ramp, said so."""
    ramp = trace.silent_after(clock)
    if ramp is None:
        return "ramp not finished in view"
    level_v, loud_ms = ramp
    if level_v == 0.0 and loud_ms == 0.0:
        return "already silent: no ramp"
    sample_ms = 1e3 / trace.sample_rate_hz
    digits = max(1, 1 - int(np.floor(np.log10(sample_ms))))  # a sample shows
    return f"ramp {level_v:.1f} V -> 0 V in {loud_ms + sample_ms:.{digits}f} ms"


def marks_lines(trace) -> list[str]:
    """One line per e-stop or fault in ``trace``: when, from what level, how long the
    ramp to silence took (as the trace shows it)."""
    lines = []
    for clock, kind, message in trace.marks:
        if kind not in ("estop", "fault"):
            continue
        at_ms = (clock - trace.clock) * 1e3 / trace.sample_rate_hz
        lines.append(f"{kind} at {at_ms:.1f} ms: {ramp_words(trace, clock)} ({message})")
    return lines


class ScopePane(ScopeRecordingMixin, Vertical):
    HELP_TEXT = (
        "space    freeze / run (frozen: the last 4 s are kept to look at)\n"
        "p        the last played plan, whole (frozen until the next plan plays)\n"
        "+ / -    shorter / longer time window (on the last plan: around its middle,\n"
        "         - back out to the whole plan)\n"
        "o        a recording (Studies: record trials; a demo from a shell: haptable demo\n"
        "         flow --record FILE; one started here: [recording] enabled = true in\n"
        "         the profile): type its path, Enter shows its plans (re-rendered from\n"
        "         their recorded parameters, the hash checked)\n"
        "[ / ]    in a recording: the previous / next plan\n"
        "e        in a recording: the gate's own events of the run (relay switches,\n"
        "         e-stops, resets, faults, refusals, with their gate clocks)\n"
        "Esc      the live view again\n"
        "What the safety gate handed the driver, per channel, in volts at the actuators."
    )
    BINDINGS = [
        Binding("space", "freeze", "Freeze/run"),
        Binding("p", "last_plan", "Last plan"),
        Binding("plus,equals_sign", "zoom(-1)", "Shorter", show=False),
        Binding("minus", "zoom(1)", "Longer", show=False),
        *SCOPE_REPLAY_BINDINGS,
    ]
    can_focus = True

    def __init__(self, **kw) -> None:
        super().__init__(**kw)
        self.window_ms = 50
        self.frozen = None  # the whole ring (ScopeTrace) while frozen
        self.plan_view = False  # frozen on the last plan's span
        self.plan_key = None  # the key of the KernelPlan frozen on (``p``)
        self.plan_done = False  # it had ended when the ring was frozen
        self.plan_window_ms: int | None = None  # on the last plan: None = all of it
        self.last = None  # the last plan the gate passed (``KernelPlan``), as last read
        self.shown = None  # the ScopeTrace drawn now
        self._timer = None  # the live view's, while the screen shows
        self._drawn: tuple | None = None  # what the chart shows (``_signature``)
        self._head = ""  # what the header says
        self.draws = 0  # how often the chart was drawn (tests count it)

    def compose(self) -> ComposeResult:
        yield KeptText("", id="scope-head", markup=False)  # "50 ms" never split
        yield Chart(
            x_label="time",
            x_unit="ms",
            y_label="output",
            y_unit="V",
            zero_y=True,  # a voltage axis shows its zero
            id="scope-chart",
        )
        yield Static("", id="scope-info", markup=False)

    @property
    def focus_target(self):
        return self

    def on_mount(self) -> None:
        self._redraw()

    def set_visible(self, visible: bool) -> None:
        """Shown: the live view is read every ``TICK_S``; hidden: no timer."""
        if visible and self._timer is None:
            self._timer = self.set_interval(TICK_S, self.tick)
        elif not visible and self._timer is not None:
            self._timer.stop()
            self._timer = None

    # ------------------------------------------------------------------ keys
    def action_freeze(self) -> None:
        if self.frozen is not None:
            self.frozen, self.plan_view, self.plan_key = None, False, None
        else:
            self.frozen = self.app.session.scope(None)
        self._redraw()

    def action_last_plan(self) -> None:
        session = self.app.session
        self.last = session.last_plan()
        self.frozen = session.scope(None)
        self.plan_view = self.frozen is not None
        self.plan_key = None if self.last is None else self.last.key
        self.plan_done = self.last is not None and self.last.done
        self.plan_window_ms = None
        self._redraw()

    def action_zoom(self, step: int) -> None:
        """``+`` (-1) / ``-`` (1): a shorter / longer window; on the last plan, a window
        around its middle, ``-`` back out to the whole plan."""
        if self.plan_view:
            self._zoom_plan(step)
        else:
            i = min(range(len(WINDOWS_MS)), key=lambda k: abs(WINDOWS_MS[k] - self.window_ms))
            self.window_ms = WINDOWS_MS[min(max(i + step, 0), len(WINDOWS_MS) - 1)]
        self._redraw()

    def _zoom_plan(self, step: int) -> None:
        """The next window in ``WINDOWS_MS`` shorter than the plan's view (``step`` -1)
        or longer (1; none shorter than the whole plan: the whole plan again)."""
        trace, _mode = self._view(whole=True)
        if trace is None:
            return
        whole_ms = trace.n * 1e3 / trace.sample_rate_hz
        now = self.plan_window_ms or whole_ms
        if step < 0:
            shorter = [w for w in WINDOWS_MS if w < now]
            self.plan_window_ms = shorter[-1] if shorter else self.plan_window_ms
        else:
            longer = [w for w in WINDOWS_MS if now < w < whole_ms]
            self.plan_window_ms = longer[0] if longer else None

    # ------------------------------------------------------------------ drawing
    def tick(self) -> None:
        """Every ``TICK_S`` while the screen shows: redrawn when what it shows changed (the
        live view, the plan line, the last plan's kept copy); a new plan unfreezes the
        last plan's view."""
        if self.replay is not None:  # a recording's plans show (``scope_recording``)
            return
        session = self.app.session
        self.last = session.last_plan()
        if self.plan_view and self.last is not None and self.last.key != self.plan_key:
            self.frozen, self.plan_view, self.plan_key = None, False, None  # another plan
            self.plan_window_ms = None
        if self.plan_view and self.last is not None and self.last.done and not self.plan_done:
            self.frozen, self.plan_done = session.scope(None), True  # it ended: its end too
        # live: what the gate passed; frozen: the plan line (its state, as it changes);
        # the last plan: its copy, kept when it ended
        self._redraw(only_changed=True)

    def _view(self, whole: bool = False):
        """What to draw: the live window, the frozen window or the last plan's span
        (``plan_window_ms`` of it around its middle, unless ``whole``)."""
        trace, mode = self._whole_view()
        if whole or trace is None or not mode.startswith("frozen on") or not self.plan_window_ms:
            return trace, mode
        half = int(self.plan_window_ms * trace.sample_rate_hz / 2e3)
        middle = self._plan_middle(trace)
        return trace.span(middle - half, middle + half), mode

    def _plan_middle(self, trace) -> int:
        """The gate clock in the middle of the last plan's segments (or of ``trace``)."""
        last = self.last
        if last is not None and last.segment_start and last.segment_end:
            return (last.segment_start[0] + last.segment_end[-1]) // 2
        return trace.clock + trace.n // 2

    def _whole_view(self):
        """The live window, the frozen window or the last plan's whole span."""
        session = self.app.session
        last = self.last
        if self.frozen is None:
            trace = session.scope(self.window_ms / 1e3)
            return trace, "live"
        trace = self.frozen
        if self.plan_view and last is not None:
            report = last
            kept = session.kept_plan_trace(last)
            if kept is not None:  # copied when it ended
                gone = "" if report.segment_start[0] >= kept.clock else " (its start is gone)"
                return kept, f"frozen on the last plan{gone}"
            if report.segment_start:
                fs = trace.sample_rate_hz
                margin = int(PLAN_MARGIN_MS * fs / 1e3)
                end = report.segment_end[-1] if report.segment_end else trace.clock + trace.n
                if end + margin <= trace.clock:
                    return None, "aged out"
                kept = (
                    ""
                    if report.segment_start[0] >= trace.clock
                    else " (its start is gone: play it again)"
                )
                return (
                    trace.span(report.segment_start[0] - margin, end + margin),
                    f"frozen on the last plan{kept}",
                )
        return trace.last(self.window_ms / 1e3), "frozen"

    def _signature(self, trace, mode: str) -> tuple:
        """What a drawing of ``trace`` shows: its samples (not its clock: the live view
        of a silent gate stays the same picture), marks, mode and window."""
        if trace is None:
            return (None, mode, self.window_ms, self.app.session.outputs_error)
        volts = np.ascontiguousarray(trace.volts)
        marks = tuple((c - trace.clock, k, m) for c, k, m in trace.marks)
        return (hash(volts.tobytes()), volts.shape, marks, mode, self.window_ms)

    def _head_text(self, trace, mode: str, plan: str) -> str:
        """The header: what shows, the keys, and the last plan's line (``plan``)."""
        if trace is None and mode == "aged out":
            return (
                "FROZEN | the last plan aged out of the scope and was not kept: "
                f"play it again (space runs live) | {plan}"
            )
        if trace is None:
            return f"outputs not here: {self.app.session.outputs_error or 'not open yet'}; {plan}"
        span_ms = trace.n * 1e3 / trace.sample_rate_hz
        space = "space runs live" if self.frozen is not None else "space freezes"
        window = f"window {self.window_ms} ms"
        if mode.startswith("frozen on"):
            window = (
                f"window {self.plan_window_ms} ms around its middle"
                if self.plan_window_ms
                else "the whole plan"
            )
        return (
            f"{mode.upper()} | {span_ms:.0f} ms shown ({window}; {space}, "
            f"p last plan, +/- zoom) | {plan}"
        )

    def _redraw(self, only_changed: bool = False) -> None:
        """Draw what ``_view`` says; ``only_changed``: the chart only if its picture
        changed (the header follows the plan's state either way)."""
        chart = self.query_one("#scope-chart", Chart)
        info = self.query_one("#scope-info", Static)
        trace, mode = self._view()
        text = self._head_text(trace, mode, plan_line(self.last))
        if self.said_head:  # what o said, after the view's mode (live or frozen)
            text = f"{text.split(' | ', 1)[0]} | {self.said_head}"
        if text != self._head:
            self._head = text
            self.query_one("#scope-head", Static).update(text)
        sig = self._signature(trace, mode)
        if only_changed and sig == self._drawn:
            return  # the same picture: nothing is redrawn
        self._drawn = sig
        self.draws += 1
        self.shown = trace
        if trace is None:
            chart.clear(
                "the last plan aged out: play it again, space runs live"
                if mode == "aged out"
                else "no outputs in this console: nothing to show"
            )
            info.update("")
            return
        t_ms = np.arange(trace.n) * (1e3 / trace.sample_rate_hz)
        chart.set_series(
            [Series(ch, t_ms, trace.volts[:, c]) for c, ch in enumerate(trace.channels)],
            title="what the gate handed the driver, volts at the actuators",
        )
        peaks = ", ".join(f"{ch} {v:.1f} V" for ch, v in trace.peak_v().items())
        info.update("\n".join([f"peak: {peaks}", *marks_lines(trace)]))
