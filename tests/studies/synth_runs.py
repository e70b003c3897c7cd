"""Run folders written straight from the file contract (``README.md`` of plugins/studies),
for the analysis tests: no runner, no twin. ``write_exp2`` / ``write_exp1`` / ``write_knob``
answer with given per-cell probabilities (seeded)."""

from __future__ import annotations

import itertools
import json
from pathlib import Path

import numpy as np

DIRS = ("up", "down", "left", "right")


def _participant(root: Path, pid: str) -> Path:
    d = root / pid
    d.mkdir(parents=True, exist_ok=True)
    (d / "participant.json").write_text(
        json.dumps(
            {
                "id": pid,
                "age": 30,
                "sex": "female",
                "handedness": "right",
                "hand_width_cm": 8.5,
                "hand_length_cm": 18.4,
                "consent_noted": True,
                "consent_time": "2026-01-01T00:00:00Z",
                "simulated": True,
                "observer": {"model": "synthetic"},
            }
        )
    )
    return d


def _write(d: Path, experiment: str, trials: list[dict], done: list[dict], extra=()) -> None:
    plan = {"experiment": experiment, "participant": d.name, "seed": 1, "trials": trials}
    (d / "plan.json").write_text(json.dumps(plan))
    with open(d / "trials.jsonl", "w") as f:
        for rec in list(done) + list(extra):
            f.write(json.dumps(rec) + "\n")


def write_flow(
    root: Path,
    experiment: str,
    places: tuple[str, ...],
    p_correct,
    n_participants: int,
    reps: int,
    *,
    seed: int = 0,
    drop: dict[str, int] | None = None,
) -> Path:
    """exp1 (places = pairs) or exp2 (regions): ``p_correct(pid_index, place, direction)``;
    ``drop``: participant -> number of main trials left undone at the end."""
    key = "pair" if experiment == "exp1" else "region"
    dirs = ("left_to_right", "right_to_left") if experiment == "exp1" else DIRS
    rng = np.random.default_rng(seed)
    for i in range(n_participants):
        pid = f"P{i + 1:02d}"
        d = _participant(root, pid)
        trials = []
        for k in range(4):  # a practice phase
            trials.append(
                {
                    "index": len(trials),
                    "phase": "practice",
                    key: "F",
                    "direction": dirs[k % len(dirs)],
                    "stimulus": {},
                }
            )
        for place, dr in itertools.product(places, dirs):
            for _ in range(reps):
                trials.append(
                    {
                        "index": len(trials),
                        "phase": "main",
                        key: place,
                        "direction": dr,
                        "stimulus": {},
                    }
                )
        done = []
        n_keep = len(trials) - (drop or {}).get(pid, 0)
        for t in trials[:n_keep]:
            p = 0.9 if t["phase"] == "practice" else p_correct(i, t[key], t["direction"])
            ok = bool(rng.random() < p)
            resp = t["direction"] if ok else [x for x in dirs if x != t["direction"]][0]
            done.append(
                {
                    "event": "done",
                    "participant": pid,
                    "experiment": experiment,
                    "phase": t["phase"],
                    "trial": t["index"],
                    "pair": t.get("pair"),
                    "region": t.get("region"),
                    "direction": t["direction"],
                    "condition": None,
                    "stimulus": {},
                    "response": resp,
                    "correct": ok,
                    "replays": 0,
                    "response_time_s": 1.0,
                    "t_start": 0.0,
                    "t_end": 1.0,
                }
            )
        _write(d, experiment, trials, done)
    return root


CONDITIONS = ("V", "HD", "HD+CF", "HD+VF")
CATEGORIES = ("effectiveness", "ease of use")


def write_knob(root: Path, n_participants: int, reps: int = 2, *, seed: int = 0) -> Path:
    """Knob runs: completion time grows with sectors and distance, overshoots with sectors,
    the questionnaire favours the haptic conditions."""
    rng = np.random.default_rng(seed)
    for i in range(n_participants):
        pid = f"P{i + 1:02d}"
        d = _participant(root, pid)
        trials, done, quest = [], [], []
        for c, s, dist in itertools.product(CONDITIONS, (8, 16, 32), (135, 270, 450)):
            for _ in range(reps):
                idx = len(trials)
                trials.append(
                    {
                        "index": idx,
                        "phase": "main",
                        "condition": c,
                        "stimulus": {
                            "task": "knob",
                            "condition": c,
                            "sectors": s,
                            "distance_deg": float(dist),
                        },
                    }
                )
                ct = 0.8 + 0.01 * s + 0.002 * dist + rng.normal(0, 0.2) + 0.1 * i
                ov = int(rng.poisson(0.2 + s / 40))
                done.append(
                    {
                        "event": "done",
                        "participant": pid,
                        "experiment": "knob",
                        "phase": "main",
                        "trial": idx,
                        "condition": c,
                        "stimulus": trials[-1]["stimulus"],
                        "response": None,
                        "correct": True,
                        "replays": 0,
                        "response_time_s": None,
                        "completion_time_s": ct,
                        "overshoots": ov,
                        "recovery_time_s": (0.3 + 0.01 * s + rng.normal(0, 0.05)) if ov else None,
                        "sectors": s,
                        "distance_deg": float(dist),
                        "t_start": 0.0,
                        "t_end": 1.0,
                    }
                )
            for cat in CATEGORIES:
                for item in (1, 2):
                    base = 3.0 if c == "V" else 5.0
                    quest.append(
                        {
                            "event": "questionnaire",
                            "participant": pid,
                            "experiment": "knob",
                            "after_trial": len(trials) - 1,
                            "condition": c,
                            "category": cat,
                            "item": item,
                            "score": int(np.clip(round(base + rng.normal(0, 0.8)), 1, 7)),
                        }
                    )
        _write(d, "knob", trials, done, quest)
    return root
