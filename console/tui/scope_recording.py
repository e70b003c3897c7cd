"""A recorded run's plans on the Scope screen (issue 31): ``o`` types a recording's path,
then the Scope shows its plans one at a time on the chart it uses for a live plan, ``[`` /
``]`` step between them, ``e`` lists the kernel's own gate events of the run (relay
switches, e-stops, resets, faults, refusals, with their gate clocks), ``escape`` goes back
to the live view.

A recording keeps each plan's parameters (``meta``), the hash of its samples and the
kernel's clocks, not the samples: a plan is drawn re-rendered from its recorded
parameters through the effect that rendered it (``RENDERERS``: every flow the console
plays, under a hand or between two points, at the part volts recorded) on the map the
run kept (``KeepsItsMap``: a study's trial), else the console's, else the kept measured
map the demos use, and the hash says whether the re-rendered samples are bit for bit
those played. A plan of a kind with no renderer here is shown as its summary only. The file is read through the
capability ``ReadsRecordings`` and plans are rendered in a worker."""

from __future__ import annotations

import re
from typing import Any

import numpy as np
from textual.binding import Binding
from textual.widgets import Input, Static

from console.core.errors import UserError
from console.core.words import AT_CONSOLE, worded
from console.tui.charts import Chart, Series
from console.tui.checked_field import refused, taken
from console.tui.field_open import opens_field, show_field
from console.tui.path_field import recording_field
from console.tui.recording_view import open_run
from console.tui.safety_bar import closed_relays, relay_names
from console.tui.said import log_status
from console.tui.util import from_thread, short_path
from console.tui.workers import work

REPLAY_ACTIONS = {"plan_step", "replay_live", "gate_events"}
#: the gate events listed at most (the first ones; the count says how many there are)
MAX_EVENTS_SHOWN = 40
LIVE_ONLY = {"freeze", "last_plan", "zoom"}
#: a recording's keys pressed on the live view: what they would do, said with ``o``
RECORDING_ONLY = {
    "e": "e lists a recording's gate events",
    "left_square_bracket": "[ ] step through a recording's plans",
    "right_square_bracket": "[ ] step through a recording's plans",
}


def plan_summary(line: dict, t0_s: float | None) -> str:
    """A recorded plan in one line: name, length, where, its parts, when it played."""
    segs = line.get("segments") or []
    where = sorted({p for s in segs for p in s.get("patches", ())})
    if any(s.get("screen") for s in segs):
        where.append("screen")
    meta = line.get("meta") or {}
    parts = "; ".join(
        f"{p.get('actuator', '?')} {float(p.get('frequency_hz', 0)):.1f} Hz "
        f"{float(p.get('amplitude_v', 0)):.1f} V"
        for p in meta.get("parts") or ()
        if isinstance(p, dict)
    )
    out = f"{line.get('name', '?')}: {float(line.get('duration_s', 0)):.2f} s on "
    out += ",".join(where) or "nothing"
    if parts:
        out += f" ({parts})"
    first = line.get("t_first_sample_s")
    if first is not None and t0_s is not None:
        out += f", played at {float(first) - t0_s:.2f} s"
    if line.get("refused"):
        out += f", refused: {line['refused']}"
    return out


#: a relay switch's message, as the gate words it (``1,5``; before: ``[1, 5]``)
_SWITCHED = re.compile(r"(closed: )(\[[\d, ]*\]|[\d,]+|none)$")


def named_relays(message: str, names: dict[int, str] | None) -> str:
    """A gate event's message with the relays it closed by number and by what they
    switch, as the safety bar says them: ``relays closed: 1,5 (PA screen)``."""
    found = _SWITCHED.search(message)
    if found is None:
        return message
    closed = [int(n) for n in re.findall(r"\d+", found.group(2))]
    return message[: found.start()] + found.group(1) + closed_relays(closed, names)


def gate_events_lines(
    events: list[dict], t0_s: float | None, names: dict[int, str] | None = None
) -> str:
    """A recording's gate events, one per line: when (s from the first frame, else the
    first event), the gate clock, the kind and the message (a relay switch's relays
    named as ``names`` says: ``relay_names``)."""
    # lazy: loaded when this runs, not when the module is imported
    from console.core.gate_log import counts_text

    if not events:
        return "no gate events in this recording (none happened, or it predates them)"
    t0 = t0_s if t0_s is not None else events[0]["t_s"]
    rows = [
        f"{e['t_s'] - t0:8.3f} s  clock {e['clock']:>10}  {e['kind']:<8} "
        f"{named_relays(e['message'], names) if e['kind'] == 'switch' else e['message']}"
        for e in events[:MAX_EVENTS_SHOWN]
    ]
    more = len(events) - MAX_EVENTS_SHOWN
    tail = [f"... and {more} more"] if more > 0 else []
    return "\n".join([f"{counts_text(events)}:", *rows, *tail])


def grid_point(vmap: Any, pos_mm: Any) -> Any:
    """The grid number of ``vmap``'s point at ``pos_mm`` (a flow between grid points
    renders from their numbers, as a study's does), else ``pos_mm`` as (x, y)."""
    xy = np.asarray(pos_mm, float)
    hits = np.flatnonzero(np.all(np.asarray(vmap.points_mm) == xy, axis=1))
    return int(vmap.points[hits[0]]) if hits.size else (float(xy[0]), float(xy[1]))


def _hand_flow(vs: Any, meta: dict, name: str) -> Any:
    """A flow under a hand, as the flow demo and Scenes render it."""
    # lazy: loaded when this runs, not when the module is imported
    from console.core import contracts

    eff = vs.effect(contracts.HandFlowEffect)
    return eff.render_hand_flow(tuple(meta["center_mm"]), meta["direction"], vs.vmap)


def _two_point(vs: Any, meta: dict, name: str) -> Any:
    """A flow between two points (a study's flow, the flow demo's two resting fingers),
    through the registered ``FlowEffect`` as they render it."""
    # lazy: loaded when this runs, not when the module is imported
    from console.core import contracts

    eff = vs.effect(contracts.FlowEffect)
    a, b = (grid_point(vs.vmap, meta[k]) for k in ("from_mm", "to_mm"))
    return eff.render(from_point=a, to_point=b, vmap=vs.vmap, name=name)


#: how each kind of recorded plan is rendered again (its ``meta["kind"]``): every kind of
#: flow the console plays, through the effect that rendered it
RENDERERS = {"hand_flow": _hand_flow, "flow": _two_point, "two_point": _two_point}


def at_recorded_volts(plan: Any, meta: dict) -> Any:
    """``plan`` with each part's segment at the volts its recorded ``parts`` say (a
    study plays a flow at the participant's level: its parts scaled from the effect's)."""
    import dataclasses  # lazy: only for a plan played at another level

    want, have = meta.get("parts") or [], plan.meta.get("parts") or []
    if len(want) != len(plan.segments) or len(have) != len(want):
        return plan
    segs = []
    for seg, h, w in zip(plan.segments, have, want, strict=True):
        k = float(w.get("amplitude_v", 0)) / float(h.get("amplitude_v", 0) or 1)
        if k == 1.0:
            segs.append(seg)
            continue
        patch_v = {p: np.asarray(v) * k for p, v in seg.patch_v.items()}
        segs.append(dataclasses.replace(seg, piezo_v=np.asarray(seg.piezo_v) * k, patch_v=patch_v))
    return dataclasses.replace(plan, segments=tuple(segs))


def rerender(session: Any, line: dict, run: Any = None) -> tuple[Any, str]:
    """(the plan re-rendered from ``line``'s parameters, what its hash says), or
    (``None``, why not): on the map ``run`` was recorded with when it keeps one (a
    study's trial), else the console's. Blocking: a worker's."""
    # lazy: loaded when this runs, not when the module is imported
    from console.core import contracts
    from console.core.plan_watch import plan_hash
    from console.runtime.measured_map import kept_measured_map
    from console.session.vibration import VibrationSession

    meta = line.get("meta") or {}
    render = RENDERERS.get(meta.get("kind"))
    if render is None:
        kind = meta.get("kind") or "unnamed"
        return None, f"no renderer here for a plan of kind {kind}: its summary only"
    own = run.vibration_map() if isinstance(run, contracts.KeepsItsMap) else None
    maps = [] if own is None else [own]
    vib = session.vibration
    maps += [] if vib.current is None else [vib.current.vmap]
    try:
        kept = kept_measured_map(session.profile)
    except UserError:
        kept = None
    maps += [] if kept is None else [kept]
    if not maps:
        return None, "no vibration map to re-render it with: measure one (m) on Vibration (F3)"
    first = None
    for vmap in maps:
        vs = VibrationSession(session.profile, session.plugins, vmap)
        plan = at_recorded_volts(render(vs, meta, str(line.get("name", ""))), meta)
        if plan_hash(plan) == line.get("hash"):
            return plan, "re-rendered: the samples played, bit for bit (hash checked)"
        first = first or plan
    return first, "re-rendered, but not the samples played (hash differs: another map)"


def plan_series(plan: Any, line: dict) -> list[Series]:
    """Each patch's and the screen's drive over the plan, in volts vs ms, the segments at
    the gate clocks they played at (else end to end with the plan's gap)."""
    fs = float(plan.sample_rate_hz)
    starts = list(line.get("segment_start") or [])
    if len(starts) != len(plan.segments):
        starts, at = [], 0
        for seg in plan.segments:
            starts.append(at)
            at += seg.n_samples + int(plan.gap_s * fs)
    base = starts[0]
    n = max(s - base + seg.n_samples for s, seg in zip(starts, plan.segments, strict=True))
    drives: dict[str, np.ndarray] = {}
    for s, seg in zip(starts, plan.segments, strict=True):
        a = s - base
        names = {p: seg.patch_v.get(p, seg.piezo_v) for p in sorted(seg.patches)}
        if seg.screen:
            names["screen"] = seg.screen_v
        for name, v in names.items():
            drives.setdefault(name, np.zeros(n))[a : a + seg.n_samples] = v
    t_ms = np.arange(n) * (1e3 / fs)
    return [Series(name, t_ms, v) for name, v in sorted(drives.items())]


#: its keys (the pane lists them in its ``BINDINGS``: Textual takes a widget class's only)
SCOPE_REPLAY_BINDINGS = [
    Binding("o", "open_recording", "recording"),
    Binding("right_square_bracket", "plan_step(1)", "plan", key_display="[ ]"),
    Binding("left_square_bracket", "plan_step(-1)", "previous plan", show=False),
    Binding("e", "gate_events", "gate events"),
    Binding("escape", "replay_live", "live"),
]


class ScopeRecordingMixin:
    """The Scope pane's recorded plans (mixed into ``ScopePane``)."""

    replay: Any = None  # the open recording while its plans show
    replay_plans: list = []  # its plan lines (``kind`` "plan")
    replay_i = 0  # the plan shown
    _replay_typed: str | None = None
    #: what ``o`` said (a refusal, "opening ..."): shown instead of the live header until
    #: the operator's next ``o`` or Esc, so that the live tick does not wipe it at once
    said_head: str | None = None
    _noted = False  # ``said_head`` says what a recording's key does (``RECORDING_ONLY``)

    def on_mount(self) -> None:
        box = recording_field("scope-recording")  # labelled: what to type
        self.mount(box, after="#scope-head")

    def check_action(self, action: str, parameters: tuple) -> bool | None:
        found = self.query("#scope-recording")
        if found and found.first().has_focus:
            return False
        if action in REPLAY_ACTIONS:
            return self.replay is not None
        return not (self.replay is not None and action in LIVE_ONLY)

    def on_descendant_focus(self, _event) -> None:
        self.refresh_bindings()

    def on_descendant_blur(self, _event) -> None:
        self.refresh_bindings()

    @opens_field
    def action_open_recording(self) -> None:
        self.said_head = None
        box = self.query_one("#scope-recording", Input)
        box.value = self._replay_typed or ""
        show_field(box)

    def on_input_submitted(self, event: Input.Submitted) -> None:
        if event.input.id != "scope-recording":
            return
        event.stop()  # open, as typed, until the file opens (``checked_field``)
        self._say(f"o: opening {event.value.strip()} ...")
        self._open_replay(event.value)

    def on_key(self, event) -> None:
        box = self.query_one("#scope-recording", Input)
        if event.key == "escape" and box.has_focus:
            event.stop()
            self.said_head = None
            box.display = False
            self.focus()
        elif box.has_focus:
            return
        elif self._noted:  # the next key takes away what a recording's key said
            self._noted, self.said_head = False, None
            self._redraw()
        if self.replay is None and not box.has_focus and event.key in RECORDING_ONLY:
            # not silence: the key is a recording's, and this is the live view
            event.stop()
            self._say(f"{RECORDING_ONLY[event.key]}: o opens one (a .h5 file's path)")
            self._noted = True
            self._redraw()  # after the view's mode: it is still the live view

    def _say(self, text: str) -> None:
        self.said_head = text
        log_status("Scope", text)  # what became of o, in the log too
        self.query_one("#scope-head", Static).update(text)
        self._head = text

    @work(thread=True, exclusive=True, group="scope-replay-open")
    def _open_replay(self, path: str) -> None:
        try:
            run = open_run(self.app.ctx.pm, path)
            plans = [p for p in run.plans() if p.get("kind") == "plan"]
            other = [p for p in run.plans() if p.get("kind") != "plan"]
        except UserError as exc:
            self._replay_typed = path
            from_thread(self.app, self._replay_refused, f"o: {worded(exc, AT_CONSOLE)}")
            return
        from_thread(self.app, self._replay_opened, run, plans, other)

    def _replay_refused(self, line: str) -> None:
        """A refused path: said, its field kept open as typed to correct it."""
        refused(self.query_one("#scope-recording", Input), self)
        self._say(line)

    def _replay_opened(self, run: Any, plans: list, other: list) -> None:
        self.said_head = None
        if self.replay is not None:
            self.replay.close()
        self._replay_typed = None
        taken(self.query_one("#scope-recording", Input), self)
        self.replay, self.replay_plans, self.replay_i = run, plans, 0
        self._other = other
        self.refresh_bindings()
        self._show_plan()

    def action_plan_step(self, step: int) -> None:
        if self.replay is not None and self.replay_plans:
            self.replay_i = min(max(self.replay_i + step, 0), len(self.replay_plans) - 1)
            self._show_plan()

    def action_gate_events(self) -> None:
        if self.replay is not None:
            names = relay_names(self.app.ctx.profile)  # what each relay switches
            text = gate_events_lines(self.replay.gate_events(), self._t0(), names)
            self.query_one("#scope-info", Static).update(text)

    def action_replay_live(self) -> None:
        self.said_head = None
        run = self.replay
        if run is None:
            return
        self.replay, self.replay_plans = None, []
        run.close()
        self._drawn = None
        self.refresh_bindings()
        self._redraw()

    def _t0(self) -> float | None:
        t = self.replay.t_capture_s
        return float(t[0]) if len(t) else None

    def _show_plan(self) -> None:
        run, plans = self.replay, self.replay_plans
        chart = self.query_one("#scope-chart", Chart)
        info = self.query_one("#scope-info", Static)
        name = short_path(run.path)
        if not plans:
            kinds = ", ".join(sorted({str(p.get("kind")) for p in self._other})) or "none"
            self._say(
                f"RECORDING {name} | no plans in it (its outputs: {kinds}) | e gate events, Esc live"
            )
            chart.clear("this recording holds no plans: o opens another, Esc the live view")
            info.update("")
            return
        line = plans[self.replay_i]
        self._say(
            f"RECORDING {name} | plan {self.replay_i + 1}/{len(plans)} "
            "([ ] other plans, e gate events, o another file, Esc live)"
        )
        info.update(
            f"plan {self.replay_i + 1}: {plan_summary(line, self._t0())}; "
            f"hash {str(line.get('hash', ''))[:12]}"
        )
        chart.clear("re-rendering the plan from its recorded parameters ...")
        self._render_plan(self.replay_i, line)

    @work(thread=True, exclusive=True, group="scope-replay-render")
    def _render_plan(self, i: int, line: dict) -> None:
        try:
            plan, said = rerender(self.app.session, line, self.replay)
        except (UserError, KeyError, TypeError, ValueError) as exc:
            plan, said = None, f"not re-rendered: {exc}"
        from_thread(self.app, self._rendered, i, line, plan, said)

    def _rendered(self, i: int, line: dict, plan: Any, said: str) -> None:
        if self.replay is None or i != self.replay_i:
            return  # another plan (or the live view) shows meanwhile
        chart = self.query_one("#scope-chart", Chart)
        info = self.query_one("#scope-info", Static)
        head = (
            f"plan {i + 1}: {plan_summary(line, self._t0())}; hash {str(line.get('hash', ''))[:12]}"
        )
        if plan is None:  # the chart says why it draws nothing; the summary, once, below
            info.update(head)
            chart.clear(said)
            return
        info.update(f"{head}: {said}")
        self.draws += 1
        chart.set_series(plan_series(plan, line), title=f"recorded plan: {line.get('name', '?')}")
