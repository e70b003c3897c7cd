"""``haptable bench psychophysics``: the adaptive procedures on simulated observers.

Per procedure ``n`` observers (100; 20 with ``--quick``) with known psychometric functions
(``adaptive_pf``: threshold uniform in -10..10 dB for QUEST+, 15..30 dB re 1 V for the
electrovibration staircases, 0.8..3 dB for the JND; slope uniform in the protocol's
``[observer] slope``, lapse likewise), each run once with its own seed:

- ``quest+ 2afc``: ``threshold_vibrotactile.toml``'s grids and family, 50 trials; error =
  posterior mean - the true threshold parameter; coverage of the 95 % interval;
- ``1u2d`` / ``1u3d``: ``threshold_electrovibration.toml``'s staircase rule (step, halving,
  stop) with ``down`` 2 / 3, at most 80 trials; error = mean of the last reversals - the
  level where the observer's p(correct) is the rule's target (70.7 % / 79.4 %, Levitt);
- ``1u3d jnd``: ``jnd_amplitude.toml`` (a Weibull of the increment, start, steps).

Convergence of a staircase: the observer's true p(correct) (guess included) at the levels
visited in the converged part (from the first reversal the threshold averages on), pooled
over observers; also at the recovered threshold, and the answers' observed proportion
correct there. The goals (issue 30): QUEST+ median |error| <= 1 dB in 50 trials,
staircases <= 1.5 dB in 80, convergence within 2 percentage points of the target.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from console.plugin_api import machine_info, summarize_s

from . import adaptive_pf as pf
from . import adaptive_protocol as ap
from .quest import QuestTrack
from .staircase import Staircase

GOAL_QUEST_DB = 1.0
GOAL_STAIR_DB = 1.5
GOAL_CONVERGENCE_PP = 2.0


def _observers(n: int, seed: int, slope: list[float], lapse: list[float], lo: float, hi: float):
    rng = np.random.default_rng(seed)
    return [
        (float(rng.uniform(lo, hi)), float(rng.uniform(*slope)), float(rng.uniform(*lapse)))
        for _ in range(n)
    ]


def _errors(err: list[float]) -> dict[str, float]:
    e = np.asarray(err, float)
    return {
        "bias_db": float(np.mean(e)),
        "median_abs_error_db": float(np.median(np.abs(e))),
        "spread_sd_db": float(np.std(e, ddof=1)),
        "p90_abs_error_db": float(np.percentile(np.abs(e), 90)),
    }


def bench_quest(n: int) -> dict[str, Any]:
    proto = ap.load("threshold_vibrotactile")
    p, o = proto.procedure, proto.observer
    err, cover, step_s = [], 0, []
    for k, (t, b, lam) in enumerate(_observers(n, 301, o["slope"], o["lapse"], -10, 10)):
        rng = np.random.default_rng([302, k])
        q = QuestTrack(
            family=p["family"], task=p["task"], stim_db=p["levels"], thresholds_db=p["thresholds"],
            slopes=np.asarray(p["slopes"]), lapses=np.asarray(p["lapses"]), max_trials=p["max_trials"],
        )  # fmt: skip
        while not q.done:
            t0 = time.perf_counter()
            x = q.level_db
            step_s.append(time.perf_counter() - t0)
            q.update(x, bool(rng.random() < pf.p_correct(x, o["family"], t, b, 0.5, lam)))
        err.append(q.threshold_db() - t)
        lo, hi = q.ci_db()
        cover += lo <= t <= hi
    return {
        "procedure": f"quest+ {p['task']} {p['family']}",
        "observers": n,
        "trials": p["max_trials"],
        **_errors(err),
        "ci95_coverage": cover / n,
        "goal_median_abs_error_db": GOAL_QUEST_DB,
        "meets_goal": float(np.median(np.abs(err))) <= GOAL_QUEST_DB,
        "next_level_s": summarize_s(step_s),
    }


def bench_staircase(n: int, name: str, down: int, jnd: bool = False) -> dict[str, Any]:
    proto = ap.load(name)
    p, o = proto.procedure, proto.observer
    fam = o["family"]
    target = pf.staircase_target(down)
    lo, hi = (0.8, 3.0) if jnd else (15.0, 30.0)  # inside the protocol's levels
    err, trials, p_visit, p_at, obs_right, obs_n = [], [], [], [], 0, 0
    for k, (t, b, lam) in enumerate(_observers(n, 400 + down, o["slope"], o["lapse"], lo, hi)):
        rng = np.random.default_rng([401, down, k])
        truth = pf.level_at(target, fam, t, b, 0.5, lam)
        s = Staircase(
            down=down, start_db=p["start_db"] if jnd else truth + float(rng.uniform(8, 14)),
            step_db=p["step_db"], halve_after=p["halve_after"], min_step_db=p["min_step_db"],
            stop_reversals=p["stop_reversals"], max_trials=p["max_trials"],
            threshold_reversals=p["threshold_reversals"], lo_db=float(p["levels"][0]),
        )  # fmt: skip
        while not s.done:
            x = s.level_db
            s.update(bool(rng.random() < pf.p_correct(x, fam, t, b, 0.5, lam)))
        trials.append(len(s.answers))
        est = s.threshold_db()
        if not np.isfinite(est):
            continue
        err.append(est - truth)
        p_at.append(float(pf.p_correct(est, fam, t, b, 0.5, lam)))
        for i in s.converged_trials():
            p_visit.append(float(pf.p_correct(s.levels[i], fam, t, b, 0.5, lam)))
            obs_right += s.answers[i]
            obs_n += 1
    conv = 100 * float(np.mean(p_visit))
    return {
        "procedure": f"staircase 1-up-{down}-down 2afc" + (" jnd" if jnd else ""),
        "protocol": name,
        "observers": n,
        "with_threshold": len(err),
        **_errors(err),
        "trials": {"median": float(np.median(trials)), "max": int(np.max(trials))},
        "target_pct": 100 * target,
        "convergence_pct_at_visited_levels": conv,
        "convergence_pct_at_threshold": 100 * float(np.mean(p_at)),
        "observed_pct_correct_converged": 100 * obs_right / max(obs_n, 1),
        "goal_median_abs_error_db": GOAL_STAIR_DB,
        "meets_goal": bool(
            float(np.median(np.abs(err))) <= GOAL_STAIR_DB
            and abs(conv - 100 * target) <= GOAL_CONVERGENCE_PP
        ),
    }


def run_bench(ctx: Any, quick: bool) -> dict[str, Any]:
    n = 20 if quick else 100
    t0 = time.perf_counter()
    rows = [
        bench_quest(n),
        bench_staircase(n, "threshold_electrovibration", 2),
        bench_staircase(n, "threshold_electrovibration", 3),
        bench_staircase(n, "jnd_amplitude", 3, jnd=True),
    ]
    table = [
        f"{r['procedure']:<32} bias {r['bias_db']:+.2f} dB  median |err| {r['median_abs_error_db']:.2f} dB"
        f"  sd {r['spread_sd_db']:.2f} dB"
        + (
            f"  convergence {r['convergence_pct_at_visited_levels']:.1f} % (target {r['target_pct']:.1f} %)"
            if "target_pct" in r
            else f"  95 % CI covers {100 * r['ci95_coverage']:.0f} %"
        )
        + ("" if r["meets_goal"] else "  MISSES GOAL")
        for r in rows
    ]
    return {
        "machine": machine_info(),
        "observers_per_procedure": n,
        "procedures": rows,
        "table": table,
        "wall_s": time.perf_counter() - t0,
    }
