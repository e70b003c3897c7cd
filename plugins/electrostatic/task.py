"""The knob task as the paper ran it (section 5.4) and a simulated finger to run it.

A trial: navigate from a start item to a target item ``distance_deg`` away (135, 270,
450 deg) on a knob of 8/16/32 sectors under one condition. Measured per trial (paper
5.5): completion time (start of the trial to the final entry on the target), overshoots
(times the selection left the target after reaching it) and recovery time (first
overshoot to the final entry). A trial ends when the selection has stayed on the target
for ``dwell_s``. Each finished trial is appended to a JSON-lines log and flushed with
``os.fsync`` (``console.plugin_api.append_json_line``) so a crash loses no finished trial;
``trial_log.read_trials`` reads it back.

``SimFinger`` is a simple human-like controller: minimum-jerk submovements toward the
target's centre whose duration follows Fitts' law and whose endpoint scatter grows with
the distance (so small sectors and long distances overshoot more), a reaction delay
before each correction, and camera-rate contact noise, lifts and id swaps.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import UserError, append_json_line

from .session import KnobSession
from .simulate import min_jerk, rotation_frames

SECTOR_SETS = (8, 16, 32)
DISTANCES_DEG = (135.0, 270.0, 450.0)
PAPER_CONDITIONS = ("V", "HD", "HD+CF", "HD+VF")


@dataclass(frozen=True)
class Trial:
    index: int
    condition: str
    sectors: int
    distance_deg: float
    start_item: int
    target_item: int
    n_items: int


def make_trials(
    conditions: Sequence[str] = PAPER_CONDITIONS,
    sectors: Sequence[int] = SECTOR_SETS,
    distances_deg: Sequence[float] = DISTANCES_DEG,
    repetitions: int = 6,
    seed: int = 1,
    margin_items: int = 4,
) -> list[Trial]:
    """The design (conditions x sectors x distances x repetitions) in a seeded random
    order, the same for every subject as in the paper (216 trials by default)."""
    combos = list(itertools.product(conditions, sectors, distances_deg, range(repetitions)))
    order = np.random.default_rng(seed).permutation(len(combos))
    trials = []
    for k, j in enumerate(order):
        cond, n, dist, _ = combos[int(j)]
        steps = dist / (360.0 / n)
        if abs(steps - round(steps)) > 1e-9:
            raise UserError(
                f"distance {dist:g} deg is not a whole number of {n}-sector items; "
                f"use a multiple of {360.0 / n:g} deg"
            )
        start = margin_items
        target = start + int(round(steps))
        trials.append(Trial(k, cond, int(n), float(dist), start, target, target + margin_items + 1))
    return trials


@dataclass(frozen=True)
class TrialResult:
    trial: int
    condition: str
    sectors: int
    distance_deg: float
    start_item: int
    target_item: int
    completion_time_s: float | None
    overshoots: int
    recovery_time_s: float | None
    confirm_time_s: float | None
    timed_out: bool
    crossings: int
    detents: int
    max_detent_latency_samples: float | None
    finger: str
    #: why the outputs stopped the trial (e-stop, fault); "" when they did not
    error: str = ""


def trial_metrics(
    item_times: Sequence[tuple[float, int]], target: int, t0_s: float = 0.0
) -> dict[str, Any]:
    """Completion time, overshoots and recovery time from (t_s, selected item) changes."""
    entries = [
        t
        for (t, it), (_, prev) in zip(item_times[1:], item_times[:-1], strict=False)
        if it == target and prev != target
    ]
    if item_times and item_times[0][1] == target:
        entries.insert(0, item_times[0][0])
    leaves = [
        t
        for (t, it), (_, prev) in zip(item_times[1:], item_times[:-1], strict=False)
        if prev == target and it != target
    ]
    final_entry = entries[-1] if entries and item_times[-1][1] == target else None
    first_over = leaves[0] if leaves else None
    return {
        "completion_time_s": None if final_entry is None else final_entry - t0_s,
        "overshoots": len(leaves),
        "recovery_time_s": None
        if (first_over is None or final_entry is None)
        else final_entry - first_over,
    }


@dataclass
class SimFinger:
    """Parameters of the simulated subject (angles in deg, times in s)."""

    reaction_s: float = 0.22
    fitts_a_s: float = 0.25
    fitts_b_s: float = 0.18
    scatter_frac: float = 0.08  # endpoint SD per degree travelled
    scatter_min_deg: float = 1.5
    noise_mm: float = 0.3
    lift_prob: float = 0.01  # per frame
    swap_prob: float = 0.005  # per frame
    grip_range_deg: float = 160.0  # how far the wrist turns in one grip
    regrip_s: float = 0.35  # lift, turn the hand back, touch again
    fps: float = 60.0

    def duration_s(self, dist_deg: float, width_deg: float) -> float:
        return self.fitts_a_s + self.fitts_b_s * math.log2(abs(dist_deg) / width_deg + 1.0)


def _session(
    trial: Trial,
    settings: Mapping[str, Any],
    limits: Mapping[str, float] | None,
    sample_rate_hz: int,
    block: int,
) -> KnobSession:
    """The knob session of one trial (sim or live): its condition, sectors and items."""
    return KnobSession(
        trial.condition,
        sectors=trial.sectors,
        settings=settings,
        limits=limits,
        sample_rate_hz=sample_rate_hz,
        block=block,
        start_item=trial.start_item,
        n_items=trial.n_items,
        record=False,
    )


def _result(
    trial: Trial, ses: KnobSession, m: dict, confirm_s: float, timed_out: bool, **kw: Any
) -> TrialResult:
    """A trial's result from its metrics ``m`` (``trial_metrics``); the times are
    ``None`` when it timed out. ``kw``: the finger-specific fields."""
    return TrialResult(
        trial=trial.index,
        condition=trial.condition,
        sectors=trial.sectors,
        distance_deg=trial.distance_deg,
        start_item=trial.start_item,
        target_item=trial.target_item,
        completion_time_s=None if timed_out else m["completion_time_s"],
        overshoots=m["overshoots"],
        recovery_time_s=None if timed_out else m["recovery_time_s"],
        confirm_time_s=None if timed_out else confirm_s,
        timed_out=timed_out,
        crossings=len(ses.crossings),
        detents=len(ses.stream.detent_log),
        **kw,
    )


def run_trial(
    trial: Trial,
    *,
    settings: Mapping[str, Any],
    limits: Mapping[str, float] | None = None,
    finger: SimFinger | None = None,
    rng: np.random.Generator | None = None,
    sample_rate_hz: int = 48000,
    block: int = 64,
    max_time_s: float = 30.0,
    render: bool = True,
) -> TrialResult:
    """Run one trial with the simulated finger closing the loop through the knob."""
    finger = finger or SimFinger()
    rng = rng or np.random.default_rng(trial.index)
    ses = _session(trial, settings, limits, sample_rate_hz, block)
    knob = ses.knob
    w = knob.width_deg
    dwell = float(settings["dwell_s"])
    dt = 1.0 / finger.fps
    half = finger.grip_range_deg / 2
    angle = knob.center_deg(trial.start_item)  # knob angle the finger is turning
    hand = -half  # wrist orientation within the grip range (what the contacts show)
    plan = None  # (t0, dur, a0, a1, hand0)
    next_plan_t = finger.reaction_s
    regrip_until = -1.0
    item_times: list[tuple[float, int]] = [(0.0, knob.item)]
    on_target_since: float | None = None
    lift_left = 0
    swapped = False
    t = 0.0
    timed_out = True
    while t <= max_time_s:
        if plan is None and t >= next_plan_t and t >= regrip_until:
            aim = knob.center_deg(trial.target_item)
            angle = ses.tracker.angle_deg  # what the knob shows now
            dist = aim - angle
            if knob.item != trial.target_item or abs(dist) > w / 2:
                sd = finger.scatter_min_deg + finger.scatter_frac * abs(dist)
                end = aim + rng.normal(0.0, sd)
                room = (half - hand) if end > angle else (-half - hand)
                if abs(end - angle) > abs(room):  # beyond the wrist's range: go as far as it turns
                    if abs(room) < 5.0:
                        regrip_until = t + finger.regrip_s
                        hand = -half if end > angle else half
                        plan = None
                    else:
                        end = angle + room
                if t >= regrip_until:
                    plan = (t, finger.duration_s(end - angle, w), angle, end, hand)
        if plan is not None:
            t0, dur, a0, a1, h0 = plan
            angle = float(min_jerk(np.array([t]), t0, dur, a0, a1)[0])
            hand = h0 + (angle - a0)
            if t >= t0 + dur:
                plan = None
                next_plan_t = t + finger.reaction_s
        # contacts for this frame (noise, occasional lift or id swap; none while regripping)
        if lift_left == 0 and rng.random() < finger.lift_prob:
            lift_left = int(rng.integers(1, 3))
        if rng.random() < finger.swap_prob:
            swapped = not swapped
        which = ("index", "thumb")[int(rng.integers(0, 2))]
        lifts = [(0, which, 1)] if lift_left > 0 else []
        if t < regrip_until:
            lifts = [(0, "both", 1)]
        lift_left = max(lift_left - 1, 0)
        (fr,) = rotation_frames(
            np.array([hand]),
            np.array([t]),
            noise_mm=finger.noise_mm,
            lift_frames=lifts,
            swap_frames=[0] if swapped else [],
            rng=rng,
        )
        if render:
            ses.render_until(t)
        ses.feed(t, fr[1])
        if knob.item != item_times[-1][1]:
            item_times.append((t, knob.item))
        if knob.item == trial.target_item:
            on_target_since = item_times[-1][0] if on_target_since is None else on_target_since
            if t - on_target_since >= dwell and plan is None:
                timed_out = False
                break
        else:
            on_target_since = None
        t += dt
    if render:
        ses.finish()
    m = trial_metrics(item_times, trial.target_item)
    lat = ses.latency_samples() if render else np.zeros(0)
    return _result(
        trial,
        ses,
        m,
        t,
        timed_out,
        max_detent_latency_samples=float(lat.max()) if lat.size else None,
        finger="sim",
    )


def run_live_trial(
    trial: Trial,
    *,
    settings: Mapping[str, Any],
    outputs: Any,
    attach: Callable[[KnobSession | None], None],
    limits: Mapping[str, float] | None = None,
    sample_rate_hz: int = 48000,
    block: int = 64,
    max_time_s: float = 30.0,
    clock: Callable[[], float] = time.monotonic,
    poll_s: float = 0.01,
) -> TrialResult:
    """One trial with live contacts: ``attach(session)`` hands the session to whatever
    feeds it camera frames (``session.feed(t_capture_s, contacts)``, same clock as
    ``clock``); its stream plays through ``outputs`` for the length of the trial."""
    ses = _session(trial, settings, limits, sample_rate_hz, block)
    dwell = float(settings["dwell_s"])
    t0 = clock()
    ses.item_log.append((t0, ses.knob.item))
    report = outputs.stream(ses.stream, name=f"knob trial {trial.index + 1}")
    attach(ses)
    timed_out = True
    t_end = t0
    try:
        while True:
            now = clock()
            log = list(ses.item_log)
            if log[-1][1] == trial.target_item and now - log[-1][0] >= dwell:
                timed_out, t_end = False, now
                break
            if now - t0 > max_time_s or getattr(report, "error", ""):
                t_end = now
                break
            time.sleep(poll_s)
    finally:
        attach(None)
        ses.stream.request_stop()
        with contextlib.suppress(TimeoutError):
            report.wait(2.0)
    m = trial_metrics(list(ses.item_log), trial.target_item, t0)
    error = getattr(report, "error", "") or ""
    return _result(
        trial,
        ses,
        m,
        t_end - t0,
        timed_out,
        max_detent_latency_samples=None,
        finger="live",
        error=error,
    )


def run_task(
    trials: Sequence[Trial],
    *,
    settings: Mapping[str, Any],
    limits: Mapping[str, float] | None = None,
    log_path: Path | None = None,
    finger: SimFinger | None = None,
    seed: int = 0,
    session: str | None = None,
    on_trial: Callable[[TrialResult], None] | None = None,
    render: bool = True,
) -> list[TrialResult]:
    """Run trials in order, logging each as it finishes."""
    session = session or time.strftime("%Y%m%dT%H%M%S", time.gmtime())
    results = []
    for tr in trials:
        res = run_trial(
            tr,
            settings=settings,
            limits=limits,
            finger=finger,
            rng=np.random.default_rng([seed, tr.index]),
            render=render,
        )
        results.append(res)
        if log_path is not None:
            append_json_line(
                log_path,
                {**asdict(res), "session": session, "seed": seed, "t_utc": time.time()},
            )
        if on_trial:
            on_trial(res)
    return results


def summarize(results: Sequence[TrialResult]) -> dict[str, dict[str, float]]:
    """Mean completion time, overshoots, recovery time per condition/sectors/distance."""
    groups: dict[str, list[TrialResult]] = {}
    for r in results:
        groups.setdefault(f"{r.condition} {r.sectors}s {r.distance_deg:g}deg", []).append(r)
    out = {}
    for k, rs in sorted(groups.items()):
        ct = [r.completion_time_s for r in rs if r.completion_time_s is not None]
        rt = [r.recovery_time_s for r in rs if r.recovery_time_s is not None]
        out[k] = {
            "n": len(rs),
            "completion_time_s": float(np.mean(ct)) if ct else float("nan"),
            "overshoots": float(np.mean([r.overshoots for r in rs])),
            "recovery_time_s": float(np.mean(rt)) if rt else float("nan"),
            "timeouts": sum(r.timed_out for r in rs),
        }
    return out
