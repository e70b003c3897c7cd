"""The flow demo (paper 5.2): a hand resting on the table feels a flow under it.

Per frame: ``scene`` (the ``flow_hand`` scene learns contacts and arrow touches; the
flow direction is the scene's selected arrow, else the demo's ``direction``) ->
``effect`` (a resting hand -> the plan for its position and direction) -> ``scheduled``
(the plan handed to the output scheduler, non-blocking).

The demo runs at once; behind it, every flow under a hand on the ``grid_mm`` grid is
chosen ahead in all four directions (the effect's atlas, cached on disk), then plans for
the scene's hand regions are prepared (exhaustive search, cached on disk): once there, the
frame that decides the gesture plays the nearest place's plan by lookup. While the hand settles, that plan is made and checked
ahead and its first segment's relays are closed (pre-armed, in silence, through the gate):
it plays at the next audio block after the decision. A hand where neither serves (no atlas, or off the
table's measured part) gets the staged search on a worker thread and its plan plays when
ready (``events`` record how late).
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from typing import Any, Protocol, runtime_checkable

import numpy as np

from console.plugin_api import DIRECTIONS_MM, Frame, JobLeft, SafetyRefusal, UserError

from .adapters import summary_parts
from .scene import SceneLink

log = logging.getLogger("haptable.demos.flow")


@runtime_checkable
class Prechecks(Protocol):
    """Outputs that check a plan ahead of playing it (``console.kernel.client``)."""

    def precheck(self, plan: Any) -> None: ...


@runtime_checkable
class Prearms(Protocol):
    """Outputs that close a plan's first relays ahead of it (``console.kernel.client``)."""

    def prearm(self, patches: frozenset[str], screen: bool) -> Any: ...

    def disarm(self) -> Any: ...


#: A resting hand this close past the border of the place pre-armed keeps that place (mm).
ARMED_SLACK_MM = 2.0
#: Direction -> unit vector in table mm (console.core.types: up = -y, as the projected arrows).
UNIT = DIRECTIONS_MM  # the projector's arrows use the same convention


def order_pair(a, b, direction: str) -> tuple[tuple[float, float], tuple[float, float]]:
    """(from, to): the flow runs from the finger behind to the finger ahead along
    ``direction``."""
    u = np.array(UNIT[direction])
    pa, pb = np.asarray(a, float), np.asarray(b, float)
    first, second = (pa, pb) if pa @ u <= pb @ u else (pb, pa)
    return (float(first[0]), float(first[1])), (float(second[0]), float(second[1]))


class StillPair:
    """Two fingertips resting apart (at least ``min_sep_mm``): their positions once per
    placement, when both stayed within ``still_mm`` for ``still_s``."""

    def __init__(
        self,
        still_mm: float = 12.0,
        still_s: float = 0.3,
        lift_s: float = 0.2,
        min_sep_mm: float = 50.0,
    ) -> None:
        self.still_mm, self.still_s, self.lift_s = still_mm, still_s, lift_s
        self.min_sep_mm = min_sep_mm
        self._t0: float | None = None
        self._ref: np.ndarray | None = None
        self._absent_since: float | None = None
        self._fired = False

    def update(self, t_s: float, pts) -> tuple | None:
        p = [np.asarray(q, float) for q in pts]
        if len(p) != 2 or np.hypot(*(p[0] - p[1])) < self.min_sep_mm:
            if self._absent_since is None:
                self._absent_since = t_s
            if t_s - self._absent_since >= self.lift_s:
                self._t0, self._ref, self._fired = None, None, False
            return None
        self._absent_since = None
        cur = np.array(sorted(tuple(q) for q in p))  # stable order: by x, then y
        if self._ref is None or np.hypot(*(cur - self._ref).T).max() > self.still_mm:
            if self._fired and self._ref is not None:
                moved = np.hypot(*(cur - self._ref).T).max()
                if moved <= 4 * self.still_mm:
                    return None
            self._t0, self._ref, self._fired = t_s, cur, False
            return None
        if self._fired or t_s - self._t0 < self.still_s:
            return None
        self._fired = True
        return (tuple(map(float, self._ref[0])), tuple(map(float, self._ref[1])))


class _Stopped(Exception):
    """The demo stopped while its preparation ran (cancels the atlas's build)."""


class FlowDemo:
    name = "flow"
    stages = ("scene", "effect", "scheduled")

    def __init__(
        self,
        profile: Any,
        plugins: Any,
        outputs: Any,
        plans: Any,
        *,
        direction: str = "right",
        snap_mm: float = 40.0,
        grid_mm: float = 10.0,
        prepare: bool = True,
        pair_plans: Any = None,
        projector: Any = None,
        still_mm: float = 12.0,
        still_s: float = 0.3,
        planner: Any = None,
        precompute: bool = True,
    ) -> None:
        self.profile, self.outputs, self.plans = profile, outputs, plans
        self.precompute = precompute  # choose every flow on the grid ahead (prepare too)
        self.direction = direction
        self.snap_mm = float(snap_mm)
        self.grid_mm = float(grid_mm)

        self.link = SceneLink(plugins, profile, "flow_hand", projector)
        self.scene = self.link.scene
        self.regions: list[tuple[float, float]] = []
        if self.scene is not None:
            self.regions = [(float(x), float(y)) for x, y, _ in self.scene.needs["flow_regions"]]
        self.prepare_regions = prepare
        self.pair_plans = pair_plans  # flows between two resting fingers (None: off)
        self.pair = StillPair(still_mm, still_s)
        #: the last flows, refusals and errors (bounded: a demo runs as long as it is used)
        self.events: deque[dict] = deque(maxlen=512)
        self.events_total = 0
        #: flows handed to the outputs (refusals and places without a flow are events,
        #: not plays), and of those the ones played after their plan was computed off
        #: the frame loop: no frame's decision scheduled them (Latency's frames omit them)
        self.played_total = 0
        self.played_late = 0
        #: the planning seconds of the last of those (the wait from the decision to the
        #: plan: Latency's ``planned off loop`` row)
        self.late_plan_s: deque[float] = deque(maxlen=512)
        self._lock = threading.Lock()
        self._report = None  # the plan playing now
        self._pending: threading.Thread | None = None
        self._running = False
        self.planner = planner  # computes plans in its own process (closed on stop)
        self._warm_key: tuple | None = None  # the plan made ahead for the hand on the table
        self._armed: tuple | None = None  # (patches, screen) the last pre-arm asked for
        self._rearm = False
        self._warm_next: tuple | None = None
        self._warm_ready = threading.Event()
        self._warm_thread: threading.Thread | None = None
        #: preparation behind the running demo (``start``): its step, or None when done
        self.preparing: dict | None = None
        self.prepared = threading.Event()
        self._prep_thread: threading.Thread | None = None
        self._progress = None  # ``start(wait=True)``'s progress

    # ------------------------------------------------------------------ lifecycle
    def start(self, progress=None, *, wait: bool = False) -> None:
        """Run at once: what the scene needs is prepared behind the running demo, on a
        thread of its own (``preparing`` says how far, ``prepared`` is set when done):
        with ``precompute``, every flow on the ``grid_mm`` grid in every direction (the
        atlas: minutes the first time, then cached), then the scene's regions in the
        demo's direction (exhaustive). Until a place is ready a hand there gets its flow
        planned when asked (1-3 s late).
        ``wait``: prepare first, here, reporting ``progress(done, total, what)`` (a
        benchmark measuring the prepared demo); raising in it cancels."""
        self._running = True
        if not self.prepare_regions:
            self.prepared.set()
            return
        if wait:
            self._progress = progress
            self._prepare()
            return
        t = threading.Thread(target=self._prepare, name="haptable-flow-prepare", daemon=True)
        self._prep_thread = t
        t.start()

    def _prepare(self) -> None:
        """The atlas, then the regions (``start``); each step's progress in ``preparing``.
        The atlas first: its workers are other processes at low priority, so the planner
        stays free for a hand placed meanwhile; the regions' reference searches run in
        the planner after it (a hand in a region has the atlas's place by then)."""
        try:
            if self.precompute and self.grid_mm > 0 and self._running:
                try:
                    if not self.plans.prepare_atlas(self.grid_mm, self._atlas_progress):
                        log.info("the hand_flow effect offers no atlas: flows planned when asked")
                except UserError as exc:  # e.g. per-patch drives: no atlas of those yet
                    log.warning("%s", exc)
            n = len(self.regions)
            if n:
                self._prep_step("the scene's regions", 0, n)
            for i, c in enumerate(self.regions):
                if not self._running:
                    return
                try:
                    self.plans.plan(c, self.direction, exhaustive=True)
                except UserError as exc:
                    log.warning("%s", exc)
                self._prep_step("the scene's regions", i + 1, n)
        except _Stopped:
            return
        except Exception:  # noqa: BLE001 - logged; the demo runs on, planning when asked
            if self._progress is not None:
                raise  # waited for: the caller's cancel or failure
            log.exception("preparing the flow demo")
        finally:
            with self._lock:
                self.preparing = None
            self.prepared.set()

    def _atlas_progress(self, done: int, total: int, what: str) -> None:
        if not self._running:
            raise _Stopped  # cancels the build: its workers are terminated
        self._prep_step("every flow on the grid (atlas)", done, total)

    def _prep_step(self, what: str, done: int, total: int) -> None:
        """``preparing``: what, done/total, and the seconds left at this step's pace."""
        with self._lock:
            prev = self.preparing
            job = prev["job"] if prev is not None and prev["what"] == what else JobLeft()
            left = job.left(done / total if total else 0.0)  # the console's one rule
            self.preparing = {
                "what": what,
                "done": done,
                "total": total,
                "job": job,
                "left_s": left,
            }
        if self._progress is not None:
            self._progress(done, total, what)

    def preparation(self) -> dict | None:
        """What is prepared behind the demo now (None: nothing, all done)."""
        with self._lock:
            p = self.preparing
        return None if p is None else {k: v for k, v in p.items() if k != "job"}

    #: how long ``stop`` gives the preparation to end: it is told (``_running``) and
    #: cancels at its next progress call (an atlas build asks it while its workers
    #: search, then terminates them); a preparation slower than that is not waited for
    PREP_STOP_WAIT_S = 2.0

    def stop(self) -> None:
        """No new flows; a flow already playing ends by its own ramps (max one plan)."""
        self._running = False
        self._disarm()
        if self.planner is not None:
            self.planner.close()  # a plan under way is abandoned
        if self._pending is not None:
            self._pending.join(5.0)
        if self._prep_thread is not None:
            self._prep_thread.join(self.PREP_STOP_WAIT_S)

    # ------------------------------------------------------------------ stages
    def current_direction(self) -> str:
        if self.scene is not None:
            sel = self.scene.state().get("selected")
            if sel:
                return str(sel)
        return self.direction

    def target(self, rest_mm) -> tuple[float, float]:
        """A resting hand near a scene region takes the region's (prepared) position;
        elsewhere the nearest place of the atlas (every flow chosen ahead), else the
        nearest point of a ``grid_mm`` grid, so a hand placed again at the same spot
        reuses its plan."""
        if self.regions:
            d = [np.hypot(rest_mm[0] - x, rest_mm[1] - y) for x, y in self.regions]
            i = int(np.argmin(d))
            if d[i] <= self.snap_mm:
                return self.regions[i]
        if self.grid_mm > 0 and self.plans is not None and self.plans.atlas is not None:
            near = self.plans.nearest(rest_mm)
            if near is not None:
                return near
        return self.snap(rest_mm)

    def prefer_armed(self, rest_mm, center) -> tuple[float, float]:
        """The place made (and pre-armed) while the hand settled when the resting
        position lies within ``ARMED_SLACK_MM`` of that place's half-step cell (a hand
        resting on the border between two places: the resting detector knows it to
        within ``still_mm`` only), else ``center``. The warm-up keeps its place the same
        way: a hand settling on a border does not switch the place it prepares from one
        frame to the next (each switch a plan to check and relays to close again)."""
        key = self._warm_key
        if key is None or key[0] == center or key[1] != self.current_direction():
            return center
        off = np.abs(np.asarray(rest_mm, float) - np.asarray(key[0], float))
        if self.grid_mm > 0 and off.max() <= self.grid_mm / 2 + ARMED_SLACK_MM:
            return key[0]
        return center

    def scene_stage(self, frame: Frame, work: dict) -> None:
        """Touches on the arrow buttons select the direction; the flow's end is shown."""
        if self.scene is None:
            return
        for c in work.get("contacts", ()):
            if c.pos_mm is not None and self.scene.hit(c.pos_mm):
                self.link.emit({"type": "touch", "pos_mm": [float(v) for v in c.pos_mm]})
        if self.scene.playing and not self.busy():
            self.link.emit({"type": "playing", "on": False})

    def snap(self, p) -> tuple[float, float]:
        g = self.grid_mm
        if g <= 0:
            return (float(p[0]), float(p[1]))
        return (float(round(p[0] / g) * g), float(round(p[1] / g) * g))

    def two_fingers(self, frame: Frame, work: dict) -> bool:
        """Two fingertips resting apart (two index fingers): the flow between them."""
        pts = [c.pos_mm for c in work.get("contacts", ()) if c.pos_mm is not None]
        hands = work.get("hands", ())
        if len(hands) > 1 or len(pts) == 2:
            got = self.pair.update(frame.t_capture_s, pts)
        else:
            got = self.pair.update(frame.t_capture_s, [])
        if got is None or self.pair_plans is None or not self._running or self.busy():
            return False
        direction = self.current_direction()
        a, b = order_pair(*got, direction)
        a, b = self.snap(a), self.snap(b)
        req = {"from_mm": a, "to_mm": b, "direction": direction}
        work["request"] = req
        plan = self.pair_plans.cached(a, b)
        if plan is None:  # computed off the frame loop (it can take a few 100 ms)
            self._compute_later(lambda: self.pair_plans.plan(a, b), req, frame)
            return False
        work["plan"] = plan
        return True

    def effect_stage(self, frame: Frame, work: dict) -> bool:
        if self.two_fingers(frame, work):
            return True
        g = work.get("gesture")
        rest = work.get("rest_mm")
        if g is None or g.name != "static_hand" or rest is None or not self._running:
            self._warm(work)
            return False
        if len(work.get("hands", ())) > 1:
            return False  # two hands: the two-finger flow decides
        if self.busy():
            return False
        center, direction = self.prefer_armed(rest, self.target(rest)), self.current_direction()
        work["request"] = {"center_mm": center, "direction": direction, "rest_mm": rest}
        try:
            center, plan = self.ready_plan(center, direction)
        except UserError as exc:  # the atlas knows there is no flow here
            self._log_event({"kind": "no_flow", "reason": str(exc), "seq": frame.seq})
            return False
        work["request"]["center_mm"] = center
        if plan is None:
            self._compute_later(lambda: self.plans.plan(center, direction), work["request"], frame)
            return False
        work["plan"] = plan
        return True

    def ready_plan(self, center, direction: str) -> tuple[tuple[float, float], Any]:
        """(place, plan) without a search: the plan made for ``center`` before, else (a
        scene region in a direction not prepared) its nearest atlas place's; plan
        ``None`` when only a search can make it. ``UserError``: no flow there."""
        plan = self.plans.lookup(center, direction)
        near = self.plans.nearest(center) if plan is None else None
        if near is not None:
            return near, self.plans.lookup(near, direction)
        return center, plan

    def _warm(self, work: dict) -> None:
        """A hand on the table not yet at rest: have the plan of the place under it made
        and checked now, on the warm-up thread, and its first relays pre-armed, so the
        frame that decides plays it at the next block (atlas places only: a search is
        never started speculatively). The hand leaving cancels the pre-arm."""
        hand = work.get("hand")
        # the classify stage's mean palm over its still window (``settle_mm``), else the
        # hand's centre (a pipeline without that stage)
        pos = (work.get("settle_mm") or hand.center_mm) if hand is not None else None
        if pos is None and self._warm_key is not None:  # the hand left: cancel the pre-arm
            self._warm_key = None
            self._disarm()
        if pos is None or self.plans is None or self.plans.atlas is None or not self._running:
            return
        # where the resting detector will say the hand rests: the classify stage's mean
        # palm over its still window (``settle_mm``), so the plan armed is the plan the
        # decision picks
        key = (self.prefer_armed(pos, self.target(pos)), self.current_direction())
        if key == self._warm_key and not (self._rearm and not self.busy()):
            return  # (a pre-arm skipped while the last flow played is tried again after)
        self._warm_key, self._rearm = key, False
        with self._lock:
            self._warm_next = key  # a newer place replaces one not started yet
            if self._warm_thread is None:
                self._warm_thread = threading.Thread(
                    target=self._warm_worker, name="haptable-flow-warm", daemon=True
                )
                self._warm_thread.start()
        self._warm_ready.set()

    def _warm_worker(self) -> None:
        while self._running:
            if not self._warm_ready.wait(0.5):
                continue  # look at _running again
            with self._lock:
                key, self._warm_next = self._warm_next, None
                self._warm_ready.clear()
            if key is None:
                continue
            try:
                _, plan = self.ready_plan(*key)
                if plan is not None and isinstance(self.outputs, Prechecks):
                    self.outputs.precheck(plan)
                    self._prearm(plan, key)
            except (UserError, SafetyRefusal):
                pass  # the deciding frame meets it again and says so
        with self._lock:
            self._warm_thread = None

    def _prearm(self, plan, key: tuple) -> None:
        """Close the relays of the plan's first segment now, in silence (the hand still
        settles): the plan then plays at the next block after the decision. Skipped by
        the outputs while anything plays or the operator's relays are set."""
        if not self._running or not isinstance(self.outputs, Prearms):
            return
        if self.busy():
            self._rearm = True  # the flow before still plays: again when it ended
            return
        with self._lock:
            if self._warm_next is not None or self._warm_key != key:
                return  # the hand moved on (its own place is armed next) or left
        first = plan.segments[0]
        want = (frozenset(first.patches), bool(first.screen))
        if self.outputs.prearm(*want) is not None:
            self._armed = want

    def _disarm(self) -> None:
        if isinstance(self.outputs, Prearms) and not self.busy():
            self.outputs.disarm()
            self._armed = None

    def scheduled_stage(self, frame: Frame, work: dict) -> None:
        self._play_request(work["plan"], work["request"], frame, late_s=0.0)

    def _play_request(self, plan, req: dict, frame: Frame, late_s: float) -> None:
        if "from_mm" in req:
            self._play(plan, None, req["direction"], None, frame, late_s=late_s, pair=req)
            return
        self._play(plan, req["center_mm"], req["direction"], req["rest_mm"], frame, late_s=late_s)

    def _log_event(self, ev: dict) -> None:
        self.events.append(ev)
        self.events_total += 1

    def stage_fns(self) -> list:
        return [
            ("scene", self.scene_stage),
            ("effect", self.effect_stage),
            ("scheduled", self.scheduled_stage),
        ]

    # ------------------------------------------------------------------ output
    def busy(self) -> bool:
        with self._lock:
            if self._pending is not None and self._pending.is_alive():
                return True
            return self._report is not None and not self._report.done.is_set()

    def _play(self, plan, center, direction, rest, frame: Frame, late_s: float, pair=None) -> None:
        first = plan.segments[0]
        prearmed = self._armed == (frozenset(first.patches), bool(first.screen))
        self._armed = None  # the plan opens its relays when it ends
        try:
            report = self.outputs.play(plan, wait=False)
        except SafetyRefusal as exc:  # e-stop active, or the gate refused the plan
            self._log_event({"kind": "refused", "reason": str(exc), "seq": frame.seq})
            return
        with self._lock:
            self._report = report
        ev = {
            "kind": "flow" if pair is None else "two_point",
            "t_arrival_s": frame.stamps_s.get("arrival"),
            "t_decided_s": frame.stamps_s.get("classify"),  # the gesture decision
            "t_scheduled_s": time.monotonic(),
            "late_s": late_s,
            "seq": frame.seq,
            "direction": direction,
            "parts": summary_parts(plan),
            "prearmed": prearmed,  # its first relays were asked for ahead (while it settled)
            "report": report,
        }
        if pair is None:
            ev["rest_mm"] = [float(rest[0]), float(rest[1])]
            ev["center_mm"] = [float(center[0]), float(center[1])]
        else:
            ev["from_mm"] = list(pair["from_mm"])
            ev["to_mm"] = list(pair["to_mm"])
        self.played_total += 1
        if late_s > 0:
            self.played_late += 1
            self.late_plan_s.append(late_s)
        self._log_event(ev)
        if self.scene is not None:
            self.link.emit({"type": "playing", "on": True})

    def _compute_later(self, make_plan, req: dict, frame: Frame) -> None:
        """Compute a plan on a worker thread, then play it (``late_s`` = the wait)."""
        t0 = time.monotonic()

        def run() -> None:
            try:
                plan = make_plan()
            except UserError as exc:
                if self._running:  # else: stopped while it was computed
                    self._log_event({"kind": "no_flow", "reason": str(exc), "seq": frame.seq})
                return
            except Exception as exc:  # never let the worker die silently
                log.exception("flow plan failed")
                self._log_event({"kind": "error", "reason": repr(exc), "seq": frame.seq})
                return
            if self._running:
                self._play_request(plan, req, frame, late_s=time.monotonic() - t0)

        th = threading.Thread(target=run, name="haptable-flow-plan", daemon=True)
        with self._lock:
            self._pending = th
        th.start()
