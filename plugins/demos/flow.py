"""The flow demo (paper 5.2): a hand resting on the table feels a flow under it.

Per frame: ``scene`` (the ``flow_hand`` scene learns contacts and arrow touches; the
flow direction is the scene's selected arrow, else the demo's ``direction``) ->
``effect`` (a resting hand -> the plan for its position and direction) -> ``scheduled``
(the plan handed to the output scheduler, non-blocking).

Plans for the scene's hand regions are prepared at start (exhaustive search, cached on
disk); a hand elsewhere gets the staged search on a worker thread and its plan plays
when ready (``events`` record how late).
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

import numpy as np

from console.errors import SafetyRefusal, UserError
from console.types import Frame

log = logging.getLogger("haptable.demos.flow")


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
    ) -> None:
        self.profile, self.outputs, self.plans = profile, outputs, plans
        self.direction = direction
        self.snap_mm = float(snap_mm)
        self.grid_mm = float(grid_mm)
        self.scene = None
        reg = plugins.of("scene").get("flow_hand")
        if reg is not None:
            self.scene = reg.factory(profile)
        self.regions: list[tuple[float, float]] = []
        if self.scene is not None:
            self.regions = [(float(x), float(y)) for x, y, _ in self.scene.needs["flow_regions"]]
        self.prepare_regions = prepare
        self.events: list[dict] = []
        self._lock = threading.Lock()
        self._report = None  # the plan playing now
        self._pending: threading.Thread | None = None
        self._running = False

    # ------------------------------------------------------------------ lifecycle
    def start(self, progress=None) -> None:
        """Prepare the plans the scene needs (its regions, the demo's direction; other
        directions are computed when first asked for). ``progress(done, total, what)``
        is called per region (the first time costs seconds per region; then cached)."""
        if self.prepare_regions:
            for i, c in enumerate(self.regions):
                if progress is not None:
                    progress(i, len(self.regions), f"flow {self.direction} at {c[0]:g},{c[1]:g} mm")
                try:
                    self.plans.plan(c, self.direction, exhaustive=True)
                except UserError as exc:
                    log.warning("%s", exc)
        self._running = True

    def stop(self) -> None:
        """No new flows; a flow already playing ends by its own ramps (max one plan)."""
        self._running = False
        t = self._pending
        if t is not None:
            t.join(5.0)

    # ------------------------------------------------------------------ stages
    def current_direction(self) -> str:
        if self.scene is not None:
            sel = self.scene.state().get("selected")
            if sel:
                return str(sel)
        return self.direction

    def target(self, rest_mm) -> tuple[float, float]:
        """A resting hand near a scene region takes the region's (prepared) position;
        elsewhere the nearest point of a ``grid_mm`` grid (the whole-table flow maps'
        step), so a hand placed again at the same spot reuses its plan."""
        if self.regions:
            d = [np.hypot(rest_mm[0] - x, rest_mm[1] - y) for x, y in self.regions]
            i = int(np.argmin(d))
            if d[i] <= self.snap_mm:
                return self.regions[i]
        g = self.grid_mm
        if g <= 0:
            return (float(rest_mm[0]), float(rest_mm[1]))
        return (float(round(rest_mm[0] / g) * g), float(round(rest_mm[1] / g) * g))

    def scene_stage(self, frame: Frame, work: dict) -> None:
        if self.scene is None:
            return
        for c in work.get("contacts", ()):
            if c.pos_mm is not None:
                self.scene.update({"type": "touch", "pos_mm": list(c.pos_mm)})

    def effect_stage(self, frame: Frame, work: dict) -> bool:
        g = work.get("gesture")
        rest = work.get("rest_mm")
        if g is None or g.name != "static_hand" or rest is None or not self._running:
            return False
        if self.busy():
            return False
        center, direction = self.target(rest), self.current_direction()
        work["request"] = {"center_mm": center, "direction": direction, "rest_mm": rest}
        plan = self.plans.cached(center, direction)
        if plan is None:
            self._compute_later(center, direction, rest, frame)
            return False
        work["plan"] = plan
        return True

    def scheduled_stage(self, frame: Frame, work: dict) -> None:
        req, plan = work["request"], work["plan"]
        self._play(plan, req["center_mm"], req["direction"], req["rest_mm"], frame, late_s=0.0)

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

    def _play(self, plan, center, direction, rest, frame: Frame, late_s: float) -> None:
        try:
            report = self.outputs.play(plan, wait=False)
        except SafetyRefusal as exc:  # e-stop active, or the gate refused the plan
            self.events.append({"kind": "refused", "reason": str(exc), "seq": frame.seq})
            return
        with self._lock:
            self._report = report
        ev = {
            "kind": "flow",
            "t_arrival_s": frame.stamps_s.get("arrival"),
            "t_scheduled_s": time.monotonic(),
            "late_s": late_s,
            "seq": frame.seq,
            "rest_mm": [float(rest[0]), float(rest[1])],
            "center_mm": [float(center[0]), float(center[1])],
            "direction": direction,
            "parts": plan.meta.get("parts", []),
            "report": report,
        }
        self.events.append(ev)
        if self.scene is not None:
            self.scene.update({"type": "playing", "on": True})

    def _compute_later(self, center, direction, rest, frame: Frame) -> None:
        t0 = time.monotonic()

        def run() -> None:
            try:
                plan = self.plans.plan(center, direction)
            except UserError as exc:
                self.events.append({"kind": "no_flow", "reason": str(exc), "seq": frame.seq})
                return
            except Exception as exc:  # never let the worker die silently
                log.exception("flow plan failed")
                self.events.append({"kind": "error", "reason": repr(exc), "seq": frame.seq})
                return
            if self._running:
                self._play(plan, center, direction, rest, frame, late_s=time.monotonic() - t0)

        th = threading.Thread(target=run, name="haptable-flow-plan", daemon=True)
        with self._lock:
            self._pending = th
        th.start()
