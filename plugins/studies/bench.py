"""``haptable bench study``: the simulated participant's predictions next to the paper,
and how fast simulated trials run.

Predictions: every region x direction of experiment 2 and every pair x direction of
experiment 1 (``studies/exp2.toml``, ``exp1.toml``: their places are PLACEHOLDERS until
read off the paper's figures) rendered by the registered effects on the profile's
measured map and answered by the registered ``SimulatedObserver`` for ``participants``
simulated people (their seeds as ``study run --simulate`` draws them) x the protocol's
repetitions; accuracy with its binomial standard error. The paper (section 5.2): every
pair 100 % in experiment 1; in experiment 2 direction and region means 90 %
(SD 3.6 / 3.1 %), left-to-right (``right``) 66.4 % in R4 and 95.5 % in R3 (Fig. 14). A cell
under ``WEAK_PCT`` is flagged.

Speed: the observer's answers per second on a rendered plan, the first answer of a plan
(its twin simulation), and the whole pipeline (``study run exp2 --simulate`` in a
subprocess: render, play through the safety gate on the twin, answer, fsync) as trials
per second with the median and p99 of a trial's duration.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import FlowEffect, HandFlowEffect, SimulatedObserver, machine_info
from console.plugin_api.runtime import measured_map

from . import protocol as protocols
from .plan import participant_seed

#: The paper's numbers (section 5.2.1, 5.2.2 and Fig. 14's caption); direction names ours.
PAPER_EXP1_PCT = 100.0
PAPER_EXP2_MEAN_PCT = 90.0
PAPER_EXP2_CELLS_PCT = {("R4", "right"): 66.4, ("R3", "right"): 95.5}
PAPER_NAMES = {
    "right": "left to right",
    "left": "right to left",
    "up": "down to up",
    "down": "up to down",
}
WEAK_PCT = 80.0


def _accuracy(
    obs, trial: dict, plan, seeds: list[int], reps: int, first_index: int
) -> tuple[float, float, float]:
    """(accuracy %, its standard error %, seconds per answer) over seeds x reps answers
    (trial indices from ``first_index``: each cell draws its own noise)."""
    right, n = 0, 0
    t0 = time.perf_counter()
    for seed in seeds:
        for r in range(reps):
            ans, _ = obs.respond({**trial, "index": first_index + r}, plan, participant_seed=seed)
            right += ans == trial["direction"]
            n += 1
    dt = (time.perf_counter() - t0) / n
    p = right / n
    return 100 * p, 100 * math.sqrt(p * (1 - p) / n), dt


def predictions(pm, profile, vmap, participants: int) -> dict[str, Any]:
    obs = pm.provider("observer", SimulatedObserver, profile, plugin_hint="twin")
    hand = pm.provider("effect", HandFlowEffect, profile, plugin_hint="vibrotactile")
    flow = pm.provider("effect", FlowEffect, profile, plugin_hint="vibrotactile")
    out: dict[str, Any] = {"participants": participants, "exp2": [], "exp1": []}
    first_s, answer_s = [], []
    for name in ("exp2", "exp1"):
        rows = out[name]
        proto = protocols.load(name)
        seeds = [participant_seed(proto, f"P{i + 1:02d}") for i in range(participants)]
        main = proto.phases[-1]
        reps = main.repetitions
        places = main.factors["region" if name == "exp2" else "pair"]
        for place in places:
            for d in main.factors["direction"]:
                if name == "exp2":
                    reg = proto.regions[place]
                    stim = {
                        "effect": "hand_flow",
                        "center_mm": list(reg["center_mm"]),
                        "direction": d,
                        "hand": reg["hand"],
                    }
                    cx, cy = reg["center_mm"]
                    t0 = time.perf_counter()
                    plan = hand.render_hand_flow((float(cx), float(cy)), d, vmap)
                else:
                    pair = proto.pairs[place]
                    a, b = (
                        (pair["left"], pair["right"])
                        if d == "left_to_right"
                        else (pair["right"], pair["left"])
                    )
                    stim = {"effect": "flow", "from_point": a, "to_point": b, **pair}
                    t0 = time.perf_counter()
                    plan = flow.render_flow(int(a), int(b), vmap)
                render_s = time.perf_counter() - t0
                trial = {
                    "index": 0,
                    "direction": d,
                    "stimulus": stim,
                    ("region" if name == "exp2" else "pair"): place,
                }
                t0 = time.perf_counter()
                obs.respond(trial, plan, participant_seed=seeds[0])
                first_s.append(time.perf_counter() - t0)
                acc, se, dt = _accuracy(obs, trial, plan, seeds, reps, 1000 * len(first_s))
                answer_s.append(dt)
                row = {
                    "region" if name == "exp2" else "pair": place,
                    "direction": d,
                    "predicted_pct": acc,
                    "se_pct": se,
                    "render_s": render_s,
                }
                if name == "exp1":
                    row["paper_pct"] = PAPER_EXP1_PCT
                elif (place, d) in PAPER_EXP2_CELLS_PCT:
                    row["paper_pct"] = PAPER_EXP2_CELLS_PCT[(place, d)]
                row["weak"] = acc < WEAK_PCT
                rows.append(row)
    e2 = out["exp2"]
    out["exp2_by_direction"] = {
        d: float(np.mean([r["predicted_pct"] for r in e2 if r["direction"] == d]))
        for d in dict.fromkeys(r["direction"] for r in e2)
    }
    out["exp2_by_region"] = {
        g: float(np.mean([r["predicted_pct"] for r in e2 if r["region"] == g]))
        for g in dict.fromkeys(r["region"] for r in e2)
    }
    out["exp2_mean_pct"] = float(np.mean([r["predicted_pct"] for r in e2]))
    out["paper_exp2_mean_pct"] = PAPER_EXP2_MEAN_PCT
    out["exp1_mean_pct"] = float(np.mean([r["predicted_pct"] for r in out["exp1"]]))
    out["weak_cells"] = [
        f"{r.get('region', r.get('pair'))} {r['direction']}: {r['predicted_pct']:.1f} %"
        for r in e2 + out["exp1"]
        if r["weak"]
    ]
    out["first_answer_s"] = {
        "median": float(np.median(first_s)),
        "p99": float(np.percentile(first_s, 99)),
    }
    out["answer_s"] = {
        "median": float(np.median(answer_s)),
        "p99": float(np.percentile(answer_s, 99)),
    }
    out["answers_per_s"] = 1.0 / float(np.median(answer_s))
    return out


def pipeline(trials: int) -> dict[str, Any]:
    """``study run exp2 --simulate`` for one participant and ``trials`` trials, timed."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [
            sys.executable,
            "-m",
            "console.cli.main",
            "study",
            "run",
            "exp2",
            "--simulate",
            "--participant",
            "P01",
            "--out",
            tmp,
            "--trials",
            str(trials),
            "--quiet",
        ]
        t0 = time.perf_counter()
        proc = subprocess.run(
            cmd, capture_output=True, text=True, timeout=1800, env=os.environ.copy()
        )
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            return {"error": (proc.stderr or proc.stdout).strip().splitlines()[-1:]}
        recs = [
            json.loads(x)
            for x in (Path(tmp) / "P01" / "trials.jsonl").read_text().splitlines()
            if '"done"' in x
        ]
    dur = np.array([r["t_end"] - r["t_start"] for r in recs])
    return {
        "trials": len(recs),
        "wall_s": wall,
        "trial_s": {"median": float(np.median(dur)), "p99": float(np.percentile(dur, 99))},
        "trials_per_s": 1.0 / float(np.median(dur)),
        "trials_per_s_with_start_up": len(recs) / wall,
    }


def table(res: dict[str, Any]) -> list[str]:
    """The predicted-vs-paper table as text lines."""
    p = res["predictions"]
    out = [f"{'exp2 cell':<16} {'predicted %':>12} {'paper %':>8}"]
    for r in p["exp2"]:
        paper = f"{r['paper_pct']:.1f}" if "paper_pct" in r else "-"
        flag = "  WEAK" if r["weak"] else ""
        out.append(
            f"{r['region'] + ' ' + r['direction']:<16} {r['predicted_pct']:7.1f} +-{r['se_pct']:3.1f}"
            f" {paper:>8}{flag}"
        )
    for d, v in p["exp2_by_direction"].items():
        out.append(f"{'direction ' + d:<16} {v:12.1f} {'~90':>8}")
    for g, v in p["exp2_by_region"].items():
        out.append(f"{'region ' + g:<16} {v:12.1f} {'~90':>8}")
    out.append(f"{'exp1 pair':<16} {'predicted %':>12} {'paper %':>8}")
    for r in p["exp1"]:
        flag = "  WEAK" if r["weak"] else ""
        out.append(
            f"{r['pair'] + ' ' + r['direction']:<16} {r['predicted_pct']:7.1f} +-{r['se_pct']:3.1f}"
            f" {r['paper_pct']:8.1f}{flag}"
        )
    return out


def run_bench(ctx: Any, quick: bool) -> dict[str, Any]:
    t0 = time.perf_counter()
    vmap = measured_map(ctx.profile, ctx.pm, None)
    res: dict[str, Any] = {"machine": machine_info(), "map_s": time.perf_counter() - t0}
    t0 = time.perf_counter()
    res["predictions"] = predictions(ctx.pm, ctx.profile, vmap, 20 if quick else 100)
    res["predictions_s"] = time.perf_counter() - t0
    res["pipeline"] = pipeline(8 if quick else 40)
    res["table"] = table(res)
    res["note"] = (
        "places are the protocols' placeholders (studies/exp1.toml, exp2.toml), not the "
        "paper's R1..R4 and pairs; the observer's distributions are assumptions "
        "(plugins/twin/plate/observer.py)"
    )
    return res
