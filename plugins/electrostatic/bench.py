"""``haptable bench knob``: crossing-to-detent latency and synthesizer CPU per block."""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import machine_info, summarize_s

from .session import KnobSession
from .settings import KNOB_DEFAULTS
from .simulate import (
    canned_rotation,
    instantaneous_freq_hz,
    min_jerk,
    rotation_frames,
    run_pipeline,
)
from .synth import CONDITIONS, KnobStream


def _pct(a: np.ndarray) -> dict[str, float]:
    if a.size == 0:
        return {"n": 0}
    return {
        "n": int(a.size),
        "p50": float(np.percentile(a, 50)),
        "p99": float(np.percentile(a, 99)),
        "max": float(a.max()),
    }


_LAST: dict[str, np.ndarray] = {}  # raw arrays of the last run, for the report's plots


def simulated_latency(
    n_events: int, fs: int = 48000, block: int = 64, seed: int = 0
) -> dict[str, Any]:
    """Crossings at random instants of a simulated clock; callback k renders samples
    [k B, (k+1) B) at time k B / fs. Latency = first detent sample - event instant,
    taken from the waveform (HD: the screen is silent between detents)."""
    rng = np.random.default_rng(seed)
    gap_s = 0.05  # longer than a detent so every onset is separate in the waveform
    t_ev = np.cumsum(rng.uniform(gap_s, 2 * gap_s, n_events))
    s = KnobStream("HD", fs, {**KNOB_DEFAULTS, "ramp_ms": 5.0})
    n_blocks = int(np.ceil((t_ev[-1] + 0.1) * fs / block))
    out = np.empty(n_blocks * block)
    j = 0
    for k in range(n_blocks):
        t_k = k * block / fs
        while j < n_events and t_ev[j] <= t_k:
            s.post(crossings=1)
            j += 1
        out[k * block : (k + 1) * block] = s.next_block(block)[1]
    on = np.abs(out) > 1e-9
    onsets = np.nonzero(on[1:] & ~on[:-1])[0] + 1
    onsets = onsets[onsets > int(0.01 * fs)]  # skip the start ramp region
    lat = []
    for t in t_ev:
        e = t * fs
        k = np.searchsorted(onsets, e)
        lat.append(onsets[k] - e if k < onsets.size else np.nan)
    lat_a = np.asarray(lat, dtype=float)
    missed = int(np.isnan(lat_a).sum())
    lat_a = lat_a[~np.isnan(lat_a)]
    _LAST["latency_samples"] = lat_a
    return {
        "events": n_events,
        "missed": missed,
        "samples": _pct(lat_a),
        "ms": _pct(lat_a / fs * 1e3),
        "within_one_block": bool(lat_a.size and lat_a.max() < block),
    }


def threaded_latency(
    duration_s: float, fs: int = 48000, block: int = 64, seed: int = 0
) -> dict[str, Any]:
    """Real threads: a paced callback loop (sleeping to each block deadline) and a poster
    thread; wall time from ``post()`` to the start of the block that carries the detent."""
    s = KnobStream("HD+VF", fs, KNOB_DEFAULTS)
    period = block / fs
    posted: dict[int, float] = {}
    consumed: dict[int, float] = {}
    done = threading.Event()
    late = [0]

    def callback_loop() -> None:
        t0 = time.perf_counter()
        k = 0
        seen = 0
        while not done.is_set():
            deadline = t0 + k * period
            now = time.perf_counter()
            if deadline > now:
                time.sleep(deadline - now)
            elif now - deadline > period:
                late[0] += 1
            t_call = time.perf_counter()
            s.next_block(block)
            log = s.detent_log
            while seen < len(log):
                consumed[log[seen][0]] = t_call
                seen += 1
            k += 1

    def poster() -> None:
        rng = np.random.default_rng(seed)
        t_end = time.perf_counter() + duration_s
        while time.perf_counter() < t_end:
            time.sleep(float(rng.uniform(0.01, 0.04)))
            t = time.perf_counter()
            (cid,) = s.post(crossings=1, velocity_deg_s=float(rng.uniform(0, 300)))
            posted[cid] = t
        time.sleep(0.05)
        done.set()

    cb = threading.Thread(target=callback_loop, daemon=True)
    po = threading.Thread(target=poster, daemon=True)
    cb.start()
    po.start()
    po.join()
    cb.join(timeout=1.0)
    lat = np.array([consumed[i] - t for i, t in posted.items() if i in consumed])
    return {
        "events": len(posted),
        "within_one_block_frac": float(np.mean(lat < period)) if lat.size else float("nan"),
        "unconsumed": len(posted) - lat.size,
        "wall_ms": summarize_s(lat),
        "blocks": _pct(lat / period),
        "late_callbacks": late[0],
    }


def cpu_per_block(n_blocks: int, fs: int = 48000, block: int = 64, seed: int = 0) -> dict[str, Any]:
    """next_block(64) timing per condition, with a crossing every ~30 ms and velocity
    changing every frame (16.7 ms)."""
    out = {}
    rng = np.random.default_rng(seed)
    for cond in CONDITIONS:
        s = KnobStream(cond, fs, KNOB_DEFAULTS)
        wall, cpu = [], []
        for k in range(n_blocks):
            if k % 13 == 0:
                s.post(angle_deg=float(k), velocity_deg_s=float(rng.uniform(0, 300)))
            if k % 23 == 0:
                s.post(crossings=1)
            c0, w0 = time.thread_time(), time.perf_counter()
            s.next_block(block)
            wall.append(time.perf_counter() - w0)
            cpu.append(time.thread_time() - c0)
        out[cond] = {"wall": summarize_s(wall), "cpu": summarize_s(cpu)}
    return {
        "per_condition": out,
        "worst_cpu_p50_ms": max(v["cpu"]["p50_ms"] for v in out.values()),
        "worst_cpu_p99_ms": max(v["cpu"]["p99_ms"] for v in out.values()),
        "worst_wall_p99_ms": max(v["wall"]["p99_ms"] for v in out.values()),
        "block_period_ms": block / fs * 1e3,
    }


def pipeline_per_frame(n_frames: int) -> dict[str, Any]:
    """Tracker + knob + post per camera frame."""
    t = np.arange(n_frames) / 60.0
    frames = rotation_frames(min_jerk(t, 0.0, t[-1], 0.0, 150.0), t, lift_frames=[(30, "index", 2)])
    ses = KnobSession("HD+VF", sectors=32, settings=KNOB_DEFAULTS, record=False)
    wall, cpu = [], []
    for tf, cs in frames:
        c0, w0 = time.thread_time(), time.perf_counter()
        ses.feed(tf, cs)
        wall.append(time.perf_counter() - w0)
        cpu.append(time.thread_time() - c0)
    return {"wall": summarize_s(wall), "cpu": summarize_s(cpu)}


def write_report(folder: Path, result: dict[str, Any]) -> Path:
    """Markdown summary plus a figure: latency histogram and an HD+VF excerpt."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    folder.mkdir(parents=True, exist_ok=True)
    fs, block = result["sample_rate_hz"], result["block"]
    r = run_pipeline(canned_rotation(), "HD+VF", sample_rate_hz=fs, block=block, sectors=16)
    t = np.arange(r.screen_v.size) / fs
    tz, f = instantaneous_freq_hz(r.screen_v, fs)
    fig, ax = plt.subplots(3, 1, figsize=(9, 8), constrained_layout=True)
    lat = _LAST.get("latency_samples", np.zeros(0))
    ax[0].hist(lat, bins=32, range=(0, block))
    ax[0].set(
        xlabel="crossing to first detent sample (samples)",
        ylabel="crossings",
        title=f"simulated callback loop, {block}-sample blocks at {fs} Hz",
    )
    ax[1].plot(t, r.screen_v, lw=0.5)
    for c in r.crossings:
        ax[1].axvline(c.t_s, color="r", lw=0.5, alpha=0.5)
    ax[1].set(xlabel="s", ylabel="screen V", title="HD+VF, canned rotation (red: crossings)")
    ts = [st.t_s for st in r.states]
    ax[2].plot(tz, f, ".", ms=2, label="zero-crossing frequency")
    v = np.abs([st.velocity_deg_s for st in r.states])
    ax[2].plot(ts, 60 + 120 * np.clip(v / 180.0, 0, 1), label="commanded from velocity")
    ax[2].set(xlabel="s", ylabel="Hz", ylim=(0, 300))
    ax[2].legend()
    png = folder / "knob.png"
    fig.savefig(png, dpi=110)
    plt.close(fig)
    sim = result["crossing_to_detent_simulated"]
    thr = result["crossing_to_detent_threaded"]
    cpu = result["synth_cpu_per_block"]
    rows = "\n".join(
        f"| {k} | {v['cpu']['p50_ms'] * 1e3:.1f} | {v['cpu']['p99_ms'] * 1e3:.1f} | {v['wall']['p99_ms'] * 1e3:.1f} |"
        for k, v in cpu["per_condition"].items()
    )
    md = folder / "knob.md"
    md.write_text(
        f"""# Knob benchmark

Machine: {", ".join(f"{k} {v}" for k, v in result["machine"].items())} (1-min load {result["load_average_1min"]:.1f})

## Crossing to detent ({block}-sample blocks, {fs} Hz; one block = {block / fs * 1e3:.3f} ms)

| loop | n | p50 | p99 | max | within one block |
|---|---|---|---|---|---|
| simulated clock (samples) | {sim["samples"]["n"]} | {sim["samples"]["p50"]:.1f} | {sim["samples"]["p99"]:.1f} | {sim["samples"]["max"]:.1f} | {sim["within_one_block"]} |
| real threads (ms) | {thr["wall_ms"]["n"]} | {thr["wall_ms"]["p50_ms"]:.3f} | {thr["wall_ms"]["p99_ms"]:.3f} | {thr["wall_ms"]["max_ms"]:.3f} | {thr["within_one_block_frac"]:.1%} |

## Synthesizer time per block (us)

| condition | CPU p50 | CPU p99 | wall p99 |
|---|---|---|---|
{rows}

![knob](knob.png)
""",
        encoding="utf-8",
    )
    return md


def run(ctx: Any, quick: bool, report_dir: str | None = None) -> dict[str, Any]:
    fs, block = 48000, 64
    prof = getattr(ctx, "profile", None)
    if prof is not None and hasattr(prof, "get"):
        fs = int(prof.get("audio.sample_rate_hz") or fs)
        block = int(prof.get("audio.block_size") or block)
    out = {
        "sample_rate_hz": fs,
        "block": block,
        "crossing_to_detent_simulated": simulated_latency(300 if quick else 3000, fs, block),
        "crossing_to_detent_threaded": threaded_latency(1.0 if quick else 5.0, fs, block),
        "synth_cpu_per_block": cpu_per_block(500 if quick else 5000, fs, block),
        "tracker_knob_per_frame": pipeline_per_frame(120 if quick else 600),
        "machine": machine_info(),
        "load_average_1min": os.getloadavg()[0],
        "note": "simulated: deterministic clock, latency from the waveform; threaded: real "
        "threads, wall time from post() to the callback that renders the detent (includes "
        "OS scheduling, so machine load shows up in p99/max); cpu = thread CPU time",
    }
    if report_dir:
        out["report"] = str(write_report(Path(report_dir), out))
    return out
