"""A trial's stimulus, through the registered effects and the outputs' safety gate.

``EffectPlayer`` renders a flow trial with the ``FlowEffect`` (from one grid point to the
other of the vibration map), a hand-flow trial with the ``HandFlowEffect`` (centred on the
region, toward the direction) and plays the plan with ``play(plan)`` (the console
session's ``play_plan``, or the outputs opened by the CLI); rendered plans are kept per
stimulus (a replay plays the same samples). Knob trials run the ``KnobTrials`` task (the
simulated finger closing the loop through the knob session), or with a person
``LiveKnob``: the knob session streams through the outputs while the camera loop's
contacts drive it, until the selection rests on the target or ``max_time_s``. The studies plugin knows
only the contracts (``console.core.contracts``), never the plugins that offer them.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import threading
from collections.abc import Callable
from typing import Any

from console.plugin_api import FlowEffect, HandFlowEffect, KnobTrials, OutputPlan, UserError

from .sensation import apply_level


def check_places(plan: dict[str, Any], vmap: Any) -> None:
    """Every pair's points are on the map, each left point left of its right point
    (smaller x); every region centre is on the table the map covers: one line otherwise."""
    seen: set[tuple[int, int]] = set()
    for t in plan["trials"]:
        s = t["stimulus"]
        if s.get("effect") == "flow" and (s["left"], s["right"]) not in seen:
            seen.add((s["left"], s["right"]))
            xl = float(vmap.points_mm[vmap.point_index(s["left"]), 0])
            xr = float(vmap.points_mm[vmap.point_index(s["right"]), 0])
            if not xl < xr:
                raise UserError(
                    f"{plan.get('protocol_file', 'protocol')}: pair {t['pair']}: left point "
                    f"{s['left']} (x = {xl:g} mm) is not left of right point {s['right']} "
                    f"(x = {xr:g} mm); swap left and right"
                )
        if s.get("effect") == "hand_flow":
            x, y = s["center_mm"]
            lo, hi = vmap.points_mm.min(axis=0), vmap.points_mm.max(axis=0)
            if not (lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1]):
                raise UserError(
                    f"{plan.get('protocol_file', 'protocol')}: region {t['region']}: centre "
                    f"({x:g}, {y:g}) mm is outside the map's grid ({lo[0]:g}..{hi[0]:g}, "
                    f"{lo[1]:g}..{hi[1]:g}) mm; move it onto the table"
                )


def _key(stim: dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(stim, sort_keys=True).encode()).hexdigest()


class EffectPlayer:
    """Flow and hand-flow trials: rendered by the effects, played by ``play(plan)``
    (which raises, or returns False, when the outputs refuse it)."""

    def __init__(
        self,
        plugins: Any,
        profile: Any,
        vmap: Any,
        play: Callable[[OutputPlan], Any],
        *,
        knob_seed: int = 0,
        live_knob: LiveKnob | None = None,
    ) -> None:
        self.plugins = plugins
        self.profile = profile
        self.vmap = vmap
        self._play = play
        self._plans: dict[str, OutputPlan] = {}
        self.knob_seed = knob_seed
        self.live_knob = live_knob

    def _effect(self, proto: type) -> Any:
        return self.plugins.provider("effect", proto, self.profile, plugin_hint="vibrotactile")

    def prepare(self, trial: dict[str, Any]) -> OutputPlan:
        """The trial's plan (rendered once per stimulus)."""
        s = trial["stimulus"]
        k = _key(s)
        plan = self._plans.get(k)
        if plan is None:
            if s.get("effect") == "flow":
                eff = self._effect(FlowEffect)
                plan = eff.render_flow(int(s["from_point"]), int(s["to_point"]), self.vmap)
            elif s.get("effect") == "hand_flow":
                eff = self._effect(HandFlowEffect)
                cx, cy = s["center_mm"]
                plan = eff.render_hand_flow((float(cx), float(cy)), s["direction"], self.vmap)
            else:
                raise UserError(f"no effect plays {s!r}")
            if s.get("level"):  # the participant's level, resolved in the plan (sensation.py)
                plan = apply_level(plan, s["level"])
            self._plans[k] = plan
        return plan

    def render_base(self, trial: dict[str, Any]) -> OutputPlan:
        """The trial's plan at the effect's own level (without the plan's ``level``)."""
        s = {k: v for k, v in trial["stimulus"].items() if k != "level"}
        return self.prepare({**trial, "stimulus": s})

    def play(self, trial: dict[str, Any], attempt: int) -> Any:
        s = trial["stimulus"]
        if s.get("task") == "knob":
            if self.live_knob is not None:
                return self.live_knob.play(trial)
            return knob_trial(self.plugins, self.profile, trial, self.knob_seed, attempt)
        plan = self.prepare(trial)
        if self._play(plan) is False:
            raise UserError(f"the outputs refused {plan.name!r}")
        return plan


def knob_trial(plugins: Any, profile: Any, trial: dict[str, Any], seed: int, attempt: int) -> Any:
    """One knob trial with the simulated finger (``contracts.KnobTrials``)."""
    s = trial["stimulus"]
    if s.get("level"):  # the participant's level, resolved in the plan (sensation_stimuli.py)
        from .sensation_stimuli import knob_profile  # lazy: knob studies with a level only

        profile = knob_profile(profile, s["level"])
    eff = plugins.provider("effect", KnobTrials, profile, plugin_hint="electrostatic")
    return eff.knob_trial(
        condition=s["condition"],
        sectors=int(s["sectors"]),
        distance_deg=float(s["distance_deg"]),
        seed=(int(seed) * 100_003 + int(trial["index"]) * 17 + attempt) % (2**63),
    )


def play_on(outputs: Any) -> Callable[[OutputPlan], bool]:
    """``play(plan)`` on outputs opened by ``console.kernel.client.open_outputs``:
    through the safety gate, blocking until played; a refusal is a ``UserError``."""

    def play(plan: OutputPlan) -> bool:
        report = outputs.play(plan, wait=False)
        report.wait(3 * plan.duration_s + 10)
        if report.error:
            raise UserError(f"{plan.name}: {report.error}")
        return True

    return play


#: a live knob trial ends after this long without reaching the target (paper task: 30 s)
LIVE_KNOB_MAX_S = 30.0


class LiveKnob:
    """Knob trials with a person: ``KnobTrials.knob_live_trial`` on ``outputs`` (through
    the gate), fed the contacts of each camera frame (``frame(frame, work)``, a camera
    loop's frame hook)."""

    def __init__(
        self,
        plugins: Any,
        profile: Any,
        outputs: Any,
        show: Callable[[dict[str, Any]], Any] | None = None,
    ) -> None:
        self.plugins = plugins
        self.profile = profile
        self.outputs = outputs
        self.show = show  # the projected knob scene's update(event), when one shows
        self._shown_at = 0.0
        self._ses: Any = None
        self._lock = threading.Lock()
        self.frames = 0

    def attach(self, ses: Any) -> None:
        with self._lock:
            self._ses = ses

    def frame(self, frame: Any, work: dict[str, Any]) -> None:
        contacts = work.get("contacts", ())
        pts = [c for c in contacts if c.pos_mm is not None] or list(contacts)
        with self._lock:
            self.frames += 1
            ses = self._ses
            if ses is not None:
                ses.feed(frame.t_capture_s, pts)
        if ses is not None and self.show is not None and frame.t_capture_s - self._shown_at >= 0.04:
            self._shown_at = frame.t_capture_s
            with contextlib.suppress(Exception):  # the projector going away never stops a trial
                self.show(ses.scene_event())

    def play(self, trial: dict[str, Any]) -> dict[str, Any]:
        s = trial["stimulus"]
        profile = self.profile
        if s.get("level"):  # the participant's level, resolved in the plan (sensation_stimuli.py)
            from .sensation_stimuli import knob_profile  # lazy: knob studies with a level only

            profile = knob_profile(profile, s["level"])
        eff = self.plugins.provider("effect", KnobTrials, profile, plugin_hint="electrostatic")
        res = eff.knob_live_trial(
            condition=s["condition"],
            sectors=int(s["sectors"]),
            distance_deg=float(s["distance_deg"]),
            outputs=self.outputs,
            attach=self.attach,
            max_time_s=LIVE_KNOB_MAX_S,
        )
        if res.get("error"):
            raise UserError(f"the outputs stopped it: {res['error']}")
        return res


def play_on_session(session: Any, holder: str | None = None) -> Callable[[OutputPlan], bool]:
    """``play(plan)`` through the console session (``play_plan``: the gate, the session's
    record of what played), as ``holder`` (the run holding the outputs: ``hold_outputs``);
    a refusal says why (the e-stop and its reason), a stimulus stopped while it played
    says so (``'flow 51->52' stopped by the e-stop (...), ctrl+r resets``)."""

    def play(plan: OutputPlan) -> bool:
        why = session.play_plan_why(plan, holder=holder)
        if not why:
            return True
        if why.startswith("stopped"):  # it started: the e-stop (or a cancel) stopped it
            raise UserError(f"{plan.name!r} {why}")
        from console.plugin_api.runtime import ESTOP_FIX, ESTOP_REFUSAL  # lazy: on a refusal

        if why.startswith(ESTOP_REFUSAL):  # the e-stop came between two trials: it stopped
            # the run as it stops a trial (a shell's `haptable estop` reads as ctrl+e)
            cause = why.removeprefix(ESTOP_REFUSAL).removesuffix(f", {ESTOP_FIX}").strip()
            raise UserError(f"stopped by the e-stop {cause} before {plan.name!r}, {ESTOP_FIX}")
        raise UserError(f"the outputs refused {plan.name!r}: {why.removeprefix('refused: ')}")

    return play
