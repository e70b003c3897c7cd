"""``haptable bench selftest``: the self-test on twin tables with faults and healthy ones.

A baseline is taken once on the nominal twin (sensor exactly at the reference point, 7 g).
Each seed is then a table as a technician meets it later: its sensor noise (a seed of its
own), the sensor glued again up to 1 mm off the point with 6.7-7.3 g, and each patch's
gain (amplifier and bond) drifted by a normal 1.5 % - the healthy tables - or that plus
one fault: the piezo amplifier dead, a relay (1-4) stuck open or closed, a patch detached
(coupling 2-10 %), PA and PC swapped. A fault is *found* when the test fails, *named*
when a finding names its kind and what it hit (the relay, the patch, the channel); a
false alarm is a healthy table failing. The thresholds (``selftest.Thresholds``) are
printed beside the largest values the healthy tables showed: gain off by |dB|, the fit's
residual, the largest off-diagonal mix and the smallest diagonal one.
"""

from __future__ import annotations

import dataclasses
import os
import tempfile
import time
from typing import Any

import numpy as np

from console.plugin_api import EXCITATIONS, PATCHES, UserError
from plugins.vibrotactile.selftest import FULL, Thresholds, run_selftest

KINDS = ("healthy", "dead_channel", "relay_stuck_open", "relay_stuck_closed", "detached", "swapped")


def _table(kind: str, seed: int) -> tuple[dict, dict, tuple[str, str] | None]:
    """(twin_faults, sensor drift, expected (kind, subject)) of one table."""
    rng = np.random.default_rng([7, KINDS.index(kind), seed])
    coupling = list(1.0 + 0.015 * rng.standard_normal(4))
    drift = {
        "dx": float(rng.uniform(-1, 1)),
        "dy": float(rng.uniform(-1, 1)),
        "mass_g": float(rng.uniform(6.7, 7.3)),
        "seed": int(1000 + 97 * KINDS.index(kind) + seed),
    }
    faults: dict[str, Any] = {}
    want = None
    relay = int(rng.integers(1, 5))
    if kind == "dead_channel":
        faults["dead_channels"] = ["piezo"]
        want = ("dead_channel", "piezo")
    elif kind == "relay_stuck_open":
        faults["stuck_open"] = [relay]
        want = ("relay_stuck_open", f"relay {relay}")
    elif kind == "relay_stuck_closed":
        faults["stuck_closed"] = [relay]
        want = ("relay_stuck_closed", f"relay {relay}")
    elif kind == "detached":
        coupling[relay - 1] = float(rng.uniform(0.02, 0.10))
        want = ("detached", PATCHES[relay - 1])
    elif kind == "swapped":
        faults["swapped"] = ["PA", "PC"]
        want = ("swapped", "PA/PC")
    faults["coupling"] = coupling
    return faults, drift, want


def _place(drift: dict | None) -> Any:
    # lazy: the outputs client loads when measuring
    from console.plugin_api.runtime import move_sensor

    def place(out: Any, x: float, y: float) -> None:
        if drift is None:
            move_sensor(out, x, y, 7.0)
        else:
            move_sensor(out, x + drift["dx"], y + drift["dy"], drift["mass_g"])

    return place


def _tables(out: Any, prof: Any, base: str, n: int) -> tuple[dict, list, dict]:
    """Every kind's ``n`` tables on the twin of ``out``: counts, times, healthy margins."""
    # lazy: the outputs client loads when measuring
    from console.plugin_api.runtime import inject_twin_faults

    rows: dict[str, dict] = {}
    times: list[float] = []
    healthy: dict[str, list[float]] = {"gain_db": [], "residual": [], "off_diag": [], "diag": []}
    for kind in KINDS:
        found = named = 0
        missed: list[str] = []
        for seed in range(n):
            faults, drift, want = _table(kind, seed)
            inject_twin_faults(out, faults)
            t0 = time.perf_counter()
            r = run_selftest(out, prof, baseline=base, place=_place(drift))
            times.append(time.perf_counter() - t0)
            got = {(f["kind"], f["subject"]) for f in r["findings"]}
            found += not r["ok"]
            if kind == "healthy":
                if not r["ok"]:
                    missed.append(f"seed {seed}: {r['lines'][0]}")
                c = np.array(r["c"])
                d = np.diag(c)
                healthy["gain_db"].append(float(np.max(np.abs(20 * np.log10(d)))))
                healthy["residual"].append(float(np.max(r["residual"])))
                healthy["off_diag"].append(float(np.max(c - np.diag(d))))
                healthy["diag"].append(float(np.min(d)))
                continue
            named += want in got and len(got) == 1
            if not (want in got and len(got) == 1):
                missed.append(f"seed {seed}: want {want}, got {sorted(got)}")
        rows[kind] = {"tables": n, "failed": found, "named": named, "misses": missed[:5]}
    inject_twin_faults(out, {})
    return rows, times, healthy


def run_selftest_bench(ctx: Any, quick: bool = False, seeds: int | None = None) -> dict:
    # lazy: the outputs client loads when measuring
    from console.plugin_api.runtime import open_outputs

    n = seeds if seeds is not None else (3 if quick else 20)
    prof = ctx.profile
    if prof.get("audio.driver") != "twin":
        raise UserError(f"{prof.path}: bench selftest injects faults into the twin: use -p sim")
    data = {**prof.data, "audio": {**prof.data["audio"], "block_size": 1024}}
    prof = dataclasses.replace(prof, data=data)
    base = os.path.join(tempfile.mkdtemp(prefix="haptable-selftest-bench-"), "baseline.npz")
    with open_outputs(prof, ctx.pm, fast=True) as out:
        run_selftest(out, prof, baseline=base, save=True, place=_place(None))
        rows, times, healthy = _tables(out, prof, base, n)
    t = np.array(times)
    audio_s = FULL.repeats * (FULL.sweep_s + FULL.tail_s) * len(EXCITATIONS)
    return {
        "seeds": n,
        "false_alarms": rows["healthy"]["failed"],
        "faults": {k: v for k, v in rows.items() if k != "healthy"},
        "healthy": rows["healthy"],
        "healthy_worst": {
            "gain_db": round(max(healthy["gain_db"]), 3),
            "residual": round(max(healthy["residual"]), 4),
            "off_diagonal": round(max(healthy["off_diag"]), 4),
            "diagonal_min": round(min(healthy["diag"]), 4),
        },
        "thresholds": dataclasses.asdict(Thresholds()),
        "time_s": {
            "compute_p50": round(float(np.percentile(t, 50)), 2),
            "compute_p99": round(float(np.percentile(t, 99)), 2),
            "chirps_real_time": audio_s,
            "table_p99": round(float(np.percentile(t, 99)) + audio_s, 2),
            "goal": 30.0,
            "note": "compute: the fast-forward twin's run (sensor move, plays, H1, fit); a "
            "real table adds the chirps' own time (table_p99 = both)",
        },
    }
