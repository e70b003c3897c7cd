"""``haptable bench gestures``: frame latency of the vision pipeline, and accuracy
(2-fold) vs Fourier harmonics, vs frames used for dynamic gestures, vs image noise.

Data: the dataset in ``$HAPTABLE_GESTURES_DATASET`` if set, else a synthetic set from
the camera twin with varied conditions (``synth --vary``, 2 sessions per subject) written
to a temporary folder (quick: 5 subjects x 6 reps; full: x 20). On a set with conditions,
leave-one-condition-out and light transfer (train near nominal light, test at x0.8 or
less and x1.2 or more) with harmonics and frames chosen on the training part.
"""

from __future__ import annotations

import os
import tempfile
import time
from pathlib import Path

import numpy as np

from console.bench import machine_info, summarize_s

from . import evaluate as ev
from .background import illumination, subtract
from .contacts import find_contacts
from .segmentation import body_window, contact_window, highpass_window
from .vision import VisionParams, process_frame

HARMONICS = (0, 2, 4, 6, 8, 12, 16)
NOISE = (0.0, 3.0, 6.0, 12.0)


def _dataset(quick: bool, tmp: Path) -> tuple[Path, str]:
    env = os.environ.get("HAPTABLE_GESTURES_DATASET")
    if env:
        return Path(env), env
    from .synth import synth

    reps = 6 if quick else 20
    out = tmp / "set"
    synth(out, 5, reps, seed=1, workers=1, vary=True, sessions=2)
    return out, f"twin synth --vary 5 subjects x 2 sessions x 10 gestures x {reps} reps (seed 1)"


def frame_latency(samples, params: VisionParams, n_frames: int = 300, repeats: int = 3) -> dict:
    """Per-frame pipeline time on real-size frames (wall and thread CPU time), each frame
    run ``repeats`` times: ``frame_cpu_min`` takes each frame's fastest run (the cost of
    the work itself, without other processes' interference), the others every run."""
    frames, bgs = [], []
    for s in samples[:: max(1, len(samples) // max(1, n_frames // 2))]:
        bg = s.background()
        for f in s.frames(limit=2):
            frames.append(f)
            bgs.append(bg)
    wall = np.zeros((repeats, len(frames)))
    cpu = np.zeros((repeats, len(frames)))
    steps: dict[str, list[float]] = {
        k: [] for k in ("gain", "subtract", "body", "highpass", "contacts")
    }
    for r in range(repeats):
        for i, (f, bg) in enumerate(zip(frames, bgs, strict=True)):
            c0 = time.thread_time()
            t0 = time.perf_counter()
            process_frame(f, bg, params)
            wall[r, i] = time.perf_counter() - t0
            cpu[r, i] = time.thread_time() - c0
    # the pipeline's first steps as process_frame runs them ("gain": the illumination
    # fit; "body" and "highpass" only in the windows where they can find anything)
    for f, bg in zip(frames, bgs, strict=True):
        t = time.perf_counter()
        g, o, _ = illumination(f, bg)
        steps["gain"].append(time.perf_counter() - t)
        t = time.perf_counter()
        d = subtract(f, bg, *((1.0, 0.0) if abs(g - 1) < 0.02 and abs(o) < 1.5 else (g, o)))
        steps["subtract"].append(time.perf_counter() - t)
        t = time.perf_counter()
        body_window(d, params.body_threshold, params.smooth_px)
        steps["body"].append(time.perf_counter() - t)
        t = time.perf_counter()
        win = contact_window(d, params.contact_threshold)
        hp = highpass_window(d, params.highpass_sigma_px, win) if win else None
        steps["highpass"].append(time.perf_counter() - t)
        t = time.perf_counter()
        if win:
            find_contacts(hp, params.contact_threshold, origin_px=win[:2])
        steps["contacts"].append(time.perf_counter() - t)
    h, w = frames[0].shape
    return {
        "frame_px": [int(w), int(h)],
        "frames": len(frames),
        "repeats": repeats,
        "frame_wall": summarize_s(wall.ravel()),
        "frame_cpu": summarize_s(cpu.ravel()),
        "frame_cpu_min": summarize_s(cpu.min(axis=0)),
        "steps_wall_p50_ms": {k: summarize_s(v)["p50_ms"] for k, v in steps.items()},
        "threads": "one (cv2.setNumThreads(1))",
        "load_average": list(os.getloadavg()),
    }


def run_benchmark(ctx, quick: bool) -> dict:
    import cv2

    from .dataset import load_dataset

    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        with tempfile.TemporaryDirectory(prefix="haptable-gestures-") as tmp:
            root, source = _dataset(quick, Path(tmp))
            samples = load_dataset(root)
            params = VisionParams(n_harmonics=ev.N_HARMONICS_MAX)
            lat = frame_latency(samples, params, 120 if quick else 600)
            t0 = time.perf_counter()
            fs = ev.extract(root, params)  # cached by content
            extract_s = time.perf_counter() - t0
            by_harm = []
            for n in HARMONICS:
                r = ev.cross_validate(fs, "2fold", n_harmonics=n, n_frames=4)
                from .descriptors import fourier_descriptors

                pts = np.column_stack(
                    [np.cos(np.linspace(0, 6.28, 400)), np.sin(np.linspace(0, 6.28, 400))]
                )
                ts = [0.0]
                for _ in range(200 if n >= 2 else 0):
                    t = time.perf_counter()
                    fourier_descriptors(pts, n)
                    ts.append(time.perf_counter() - t)
                by_harm.append(
                    {
                        "n_harmonics": n,
                        "static_accuracy": r["static_accuracy"],
                        "dynamic_accuracy": r["dynamic_accuracy"],
                        "descriptor_ms_p50": summarize_s(ts)["p50_ms"],
                    }
                )
            by_frames = []
            fps = float(np.median([s.fps for s in samples]))
            for k in sorted(fs.dynamic):
                r = ev.cross_validate(fs, "2fold", n_harmonics=2, n_frames=k)
                by_frames.append(
                    {
                        "frames": k,
                        "dynamic_accuracy": r["dynamic_accuracy"],
                        "kind_accuracy": r["kind_accuracy"],
                        "static_accuracy": r["static_accuracy"],
                        "decision_ms": 1e3 * (k - 1) / fps + lat["frame_cpu_min"]["p99_ms"],
                    }
                )
            by_noise = []
            sub = samples[:: max(1, len(samples) // (150 if quick else 400))]
            for sigma in NOISE:
                by_noise.append({"noise_sigma": sigma, **_noisy_accuracy(sub, params, sigma)})
            loso = ev.cross_validate(fs, "loso", n_harmonics=2, n_frames=4)
            two = ev.cross_validate(fs, "2fold", n_harmonics=2, n_frames=4)
            from .selection import condition_report

            loso_sel = ev.cross_validate(fs, "loso", n_harmonics=None, n_frames=None)
            conds = {s.name: s.meta for s in samples}
            by_condition = condition_report(fs, conds)
    finally:
        cv2.setNumThreads(threads)
    return {
        "data": source,
        "samples": len(samples),
        "latency": lat,
        "extract_s": extract_s,
        "two_fold": {k: two[k] for k in ("static_accuracy", "dynamic_accuracy", "kind_accuracy")},
        "loso": {k: loso[k] for k in ("static_accuracy", "dynamic_accuracy", "kind_accuracy")},
        "loso_selected": {
            **{k: loso_sel[k] for k in ("static_accuracy", "dynamic_accuracy", "kind_accuracy")},
            "chosen_per_fold": loso_sel["selection"]["chosen_per_fold"],
        },
        **by_condition,
        "accuracy_vs_harmonics": by_harm,
        "accuracy_vs_frames": by_frames,
        "accuracy_vs_noise": by_noise,
        "machine": machine_info(),
        "quick": quick,
    }


def _noisy_accuracy(samples, params: VisionParams, sigma: float, seed: int = 0) -> dict:
    """2-fold accuracy when Gaussian noise of ``sigma`` grey levels is added to every frame."""
    rng = np.random.default_rng(seed)
    labels, subjects, xs_all, xk_all, xd_all, sc_all = [], [], [], [], [], []
    for s in samples:
        frames = s.frames(limit=4).astype(np.float32)
        if sigma > 0:
            frames = frames + rng.normal(0, sigma, frames.shape).astype(np.float32)
        frames = np.clip(frames, 0, 255).astype(np.uint8)
        recs = ev.sample_records(frames, s.background(), params)
        xs, xk, xd, sc = ev.record_features(recs, (4,), ev.N_HARMONICS_MAX)
        xk_all.append(xk[4])
        labels.append(s.gesture)
        subjects.append(s.subject)
        xs_all.append(xs[4])
        xd_all.append(xd[4])
        sc_all.append(sc[4])
    fs = ev.FeatureSet(
        [s.name for s in samples],
        np.array(labels),
        np.array(subjects),
        {4: np.array(xs_all)},
        {4: np.array(xk_all)},
        {4: np.array(xd_all)},
        {4: np.array(sc_all)},
        np.zeros(0),
        {"n_harmonics_max": ev.N_HARMONICS_MAX},
    )
    r = ev.cross_validate(fs, "2fold", n_harmonics=2, n_frames=4)
    return {
        "static_accuracy": r["static_accuracy"],
        "dynamic_accuracy": r["dynamic_accuracy"],
        "samples": len(samples),
    }
