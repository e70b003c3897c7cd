"""``haptable bench twin-camera``: how fast the camera twin renders and writes datasets."""

from __future__ import annotations

import os
import tempfile
import time
from typing import Any

import numpy as np


def run(ctx: Any = None, quick: bool = False) -> dict:
    """Frame render time per gesture (p50/p99), PNG write time, and synth throughput
    (extrapolated to the paper's 2000 samples)."""
    from console.bench import machine_info, summarize_s

    from .gestures import GESTURES
    from .render import Rig
    from .sample import render_frame, render_sample

    rig = Rig()
    render_sample("drag", "s1", 0, np.random.default_rng(0), rig=rig)  # warm caches
    reps = 2 if quick else 8
    per_gesture = {}
    all_s: list[float] = []
    cpu_s: list[float] = []
    from .gestures import plan_take, take_pose
    from .hand import make_subject

    for g in GESTURES:
        times = []
        for rep in range(reps):
            rng = np.random.default_rng(rep)
            subj = make_subject(f"s{rep % 5 + 1}")
            take = plan_take(g, subj, rng, rig.mapping.table_mm)
            for k in range(8):
                pose = take_pose(take, k / 60.0, rng)
                t0, c0 = time.perf_counter(), time.process_time()
                render_frame([(subj, pose)], rig, k / 60.0, rng, label=g)
                times.append(time.perf_counter() - t0)
                cpu_s.append(time.process_time() - c0)
        per_gesture[g] = summarize_s(times)
        all_s += times
    empty = []
    for k in range(20):
        t0 = time.perf_counter()
        render_frame([], rig, k / 60.0, np.random.default_rng(k))
        empty.append(time.perf_counter() - t0)

    from plugins.gestures.dataset import write_png
    from plugins.gestures.synth import synth

    frames, _ = render_sample("open_hand", "s1", 0, np.random.default_rng(1), rig=rig)
    png = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(20):
            t0 = time.perf_counter()
            write_png(os.path.join(tmp, f"f{i}.png"), frames[i % len(frames)])
            png.append(time.perf_counter() - t0)
        sreps = 1 if quick else 4
        info = synth(os.path.join(tmp, "ds"), subjects=1, reps=sreps, workers=1, force=True)
        size = sum(
            os.path.getsize(os.path.join(d, f))
            for d, _, fs in os.walk(os.path.join(tmp, "ds"))
            for f in fs
        )
    per_sample_s = info["seconds"] / info["samples"]
    cores = os.cpu_count() or 1
    return {
        "frame_render": summarize_s(all_s),
        # CPU time of this process (all threads): robust when other jobs load the machine
        "frame_render_cpu": summarize_s(cpu_s),
        "frame_render_empty_table": summarize_s(empty),
        "frame_render_per_gesture": per_gesture,
        "png_write": summarize_s(png),
        "synth_one_process": {
            "samples": info["samples"],
            "seconds": info["seconds"],
            "s_per_sample": round(per_sample_s, 4),
            "bytes_per_sample": int(size / info["samples"]),
        },
        "synth_2000_estimate_s": round(2000 * per_sample_s / cores, 1),
        "synth_2000_estimate_bytes": int(2000 * size / info["samples"]),
        "load_average_1min": os.getloadavg()[0],
        "machine": machine_info(),
        "quick": quick,
    }
