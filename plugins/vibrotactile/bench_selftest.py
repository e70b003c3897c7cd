"""``haptable bench selftest``: the self-test on twin tables with faults and healthy ones.

A baseline is taken once on the nominal twin (sensor exactly at the reference point, 7 g).
Each seed is then a table as a technician meets it later: its sensor noise (a seed of its
own), the sensor glued again up to 1 mm off the point with 6.7-7.3 g, and each patch's
gain (amplifier and bond) drifted by a normal 1.5 % - the healthy tables - or that plus
one fault: the piezo amplifier dead, a relay (1-4) stuck open or closed, a patch detached
(coupling 2-10 %) or cracked (``plugins.twin.crack``), PA and PC swapped. Every table is
tested twice: against the last self-test (the baseline) and against the stored vibration
map (the twin's laser map, measured without the sensor: ``selftest_map`` fits the
sensor's mass out), as on a table's first test. The amplifier monitor's test
(``selftest_monitor``) meets the same seeds healthy, with the amplifier dead and weak. A fault is *found* when the test fails, *named*
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

from console.plugin_api import EXCITATIONS, PATCHES, UserError, machine_info
from plugins.vibrotactile.selftest import FULL, Thresholds, run_selftest

KINDS = (
    "healthy",
    "dead_channel",
    "relay_stuck_open",
    "relay_stuck_closed",
    "detached",
    "cracked",
    "swapped",
)


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
    elif kind == "cracked":
        faults["cracked"] = [PATCHES[relay - 1]]
        want = ("cracked", PATCHES[relay - 1])
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


def _tables(out: Any, prof: Any, base: str, n: int, vmap: Any = None) -> tuple[dict, list, dict]:
    """Every kind's ``n`` tables on the twin of ``out``: counts, times, healthy margins."""
    # lazy: the outputs client loads when measuring
    from console.plugin_api.runtime import inject_twin_faults

    rows: dict[str, dict] = {}
    times: list[float] = []
    healthy: dict[str, list[float]] = {
        "gain_db": [],
        "residual": [],
        "off_diag": [],
        "diag": [],
        "spread_db": [],
    }
    for kind in KINDS:
        found = named = 0
        missed: list[str] = []
        for seed in range(n):
            faults, drift, want = _table(kind, seed)
            inject_twin_faults(out, faults)
            t0 = time.perf_counter()
            r = run_selftest(
                out,
                prof,
                baseline=base,
                place=_place(drift),
                vmap=vmap,
                against="map" if vmap is not None else "auto",
            )
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
                healthy["spread_db"].append(float(np.max(r["spread_db"])))
                continue
            named += want in got and len(got) == 1
            if not (want in got and len(got) == 1):
                missed.append(f"seed {seed}: want {want}, got {sorted(got)}")
        rows[kind] = {"tables": n, "failed": found, "named": named, "misses": missed[:5]}
    inject_twin_faults(out, {})
    return rows, times, healthy


def run_selftest_bench(ctx: Any, quick: bool = False, seeds: int | None = None) -> dict:
    # lazy: the outputs client loads when measuring
    from console.plugin_api.runtime import measured_map, open_outputs

    n = seeds if seeds is not None else (3 if quick else 20)
    prof = ctx.profile
    if prof.get("audio.driver") != "twin":
        raise UserError(f"{prof.path}: bench selftest injects faults into the twin: use -p sim")
    data = {**prof.data, "audio": {**prof.data["audio"], "block_size": 1024}}
    prof = dataclasses.replace(prof, data=data)
    base = os.path.join(tempfile.mkdtemp(prefix="haptable-selftest-bench-"), "baseline.npz")
    vmap = measured_map(prof, ctx.pm)  # the twin's laser map (kept after its first run)
    with open_outputs(prof, ctx.pm, fast=True) as out:
        run_selftest(out, prof, baseline=base, save=True, place=_place(None))
        rows, times, healthy = _tables(out, prof, base, n)
        map_rows, map_times, map_healthy = _tables(out, prof, base, n, vmap)
        monitor = _monitor(out, prof, n)
    t = np.array(times)
    audio_s = FULL.repeats * (FULL.sweep_s + FULL.tail_s) * len(EXCITATIONS)
    return {
        "machine": machine_info(),
        "seeds": n,
        "false_alarms": rows["healthy"]["failed"],
        "faults": {k: v for k, v in rows.items() if k != "healthy"},
        "healthy": rows["healthy"],
        "healthy_worst": {
            "gain_db": round(max(healthy["gain_db"]), 3),
            "residual": round(max(healthy["residual"]), 4),
            "off_diagonal": round(max(healthy["off_diag"]), 4),
            "diagonal_min": round(min(healthy["diag"]), 4),
            "spread_db": round(max(healthy["spread_db"]), 2),
        },
        "against_map": {
            "false_alarms": map_rows["healthy"]["failed"],
            "faults": {k: v for k, v in map_rows.items() if k != "healthy"},
            "healthy": map_rows["healthy"],
            "healthy_worst": _worst(map_healthy),
            "compute_p50_s": round(float(np.percentile(map_times, 50)), 2),
        },
        "amp_monitor": monitor,
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


def _worst(h: dict) -> dict:
    return {
        "gain_db": round(max(h["gain_db"]), 3),
        "residual": round(max(h["residual"]), 4),
        "off_diagonal": round(max(h["off_diag"]), 4),
        "diagonal_min": round(min(h["diag"]), 4),
        "spread_db": round(max(h["spread_db"]), 2),
    }


def _monitor(out: Any, prof: Any, n: int) -> dict:
    """The monitor's test on ``n`` tables per kind (healthy, amplifier dead, weak), each with
    its own input noise: (kind -> tables, failed, named)."""
    # lazy: the outputs client loads when measuring
    from console.plugin_api.runtime import inject_twin_faults
    from plugins.vibrotactile.selftest_monitor import card_specs, run_monitor_selftest

    specs = card_specs(out)
    rows, times = {}, []
    for kind, faults, want in (
        ("healthy", {}, None),
        ("dead_channel", {"dead_channels": ["piezo"]}, ("dead_channel", "piezo")),
        ("weak_channel", {"weak_channels": ["piezo"]}, ("weak_channel", "piezo")),
    ):
        failed = named = 0
        for seed in range(n):
            coupling = list(1.0 + 0.015 * np.random.default_rng([11, seed]).standard_normal(4))
            inject_twin_faults(out, {**faults, "coupling": coupling})
            t0 = time.perf_counter()
            r = run_monitor_selftest(out, prof, specs)
            times.append(time.perf_counter() - t0)
            got = {(f["kind"], f["subject"]) for f in r["findings"]}
            failed += not r["ok"]
            named += want is not None and got == {want}
        rows[kind] = {"tables": n, "failed": failed, "named": named}
    inject_twin_faults(out, {})
    return {
        "false_alarms": rows["healthy"]["failed"],
        "kinds": rows,
        "compute_p50_s": round(float(np.percentile(times, 50)), 3),
    }
