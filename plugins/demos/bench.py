"""Benchmarks of the interaction loop on the profile's devices (the twin by default).

``loop``: the knob and flow demos at the camera's rate, audio paced in real time with
the profile's blocks; per-stage and end-to-end (frame arrival -> first output sample
scheduled) p50/p99. ``soak``: the knob demo for minutes; frames dropped for processing
reasons, RSS at start and end, audio underruns, watchdog trips.
"""

from __future__ import annotations

import os
import time
from typing import Any

from console.bench import machine_info, summarize_s

TARGET_P99_MS = 5.0


def rss_mb() -> float:
    """Resident set size of this process (MB)."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def load_avg() -> list[float]:
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return []


def _audio(out) -> dict:
    a = out.status()["audio"]
    return {
        "block_size": a.get("block_size"),
        "sample_rate_hz": a.get("sample_rate_hz"),
        "block_ms": 1e3 * a.get("block_size", 0) / max(a.get("sample_rate_hz", 1), 1),
        "underruns": a.get("underruns"),
        "blocks": a.get("blocks"),
        "paced": a.get("paced"),
    }


def _run_for(run_, seconds: float) -> None:
    t0 = time.monotonic()
    while time.monotonic() - t0 < seconds:
        time.sleep(0.2)
        if run_.watchdog.tripped:
            break


def _latency_summary(snap: dict) -> dict:
    lat = snap["latency"]
    return {
        "fps": lat["fps"],
        "frames": lat["frames"],
        "dropped_queue": lat["dropped_queue"],
        "dropped_camera": lat["dropped_camera"],
        "errors": lat["errors"],
        "stages": lat["stages"],
        "end_to_end": lat["end_to_end"],
        "processing": lat["processing"],
        "capture_to_arrival": lat["capture_to_arrival"],
        "watchdog": snap["watchdog"],
    }


def run_loop(ctx: Any, quick: bool) -> dict:
    from .run import start_demo

    seconds = 6.0 if quick else 30.0
    prof, pm = ctx.profile, ctx.pm
    res: dict = {
        "machine": machine_info(),
        "load_avg_start": load_avg(),
        "camera_fps": prof.get("camera.fps"),
        "target": {"p99_processing_ms": TARGET_P99_MS, "fps": 60, "block": 64, "rate_hz": 48000},
        "seconds_per_demo": seconds,
        "end_to_end_means": "frame arrival (taken from the camera) -> the frame's output handed "
        "to the scheduler (knob: posted to the live stream, played by its next audio block; "
        "flow: the plan queued)",
    }
    with ctx.outputs(fast=False) as out:
        with start_demo("knob", prof, pm, out) as run_:
            _run_for(run_, seconds)
            run_.stop()
            res["knob"] = _latency_summary(run_.snapshot())
            res["knob"]["crossings"] = len(run_.demo.crossings)
        res["audio"] = _audio(out)
    with ctx.outputs(fast=False) as out:
        with start_demo("flow", prof, pm, out, prepare=False) as run_:
            _run_for(run_, max(seconds * 1.5, 16.0))
            run_.stop()
            snap = run_.snapshot()
            evs = run_.demo.events
        res["flow"] = _latency_summary(snap)
        flows = [e for e in evs if e.get("kind") == "flow"]
        res["flow"]["flows"] = len(flows)
        res["flow"]["trigger_to_scheduled_cached"] = summarize_s(
            [e["t_scheduled_s"] - e["t_arrival_s"] for e in flows if e["late_s"] == 0.0]
        )
        res["flow"]["plan_compute_when_not_prepared"] = summarize_s(
            [e["late_s"] for e in flows if e["late_s"] > 0.0]
        )
    k = res["knob"]
    res["p99_processing_ms"] = k["processing"]["p99_ms"]
    res["meets_target"] = bool(k["processing"]["p99_ms"] < TARGET_P99_MS)
    res["load_avg_end"] = load_avg()
    return res


def run_soak(ctx: Any, quick: bool, minutes: float | None = None) -> dict:
    """The knob demo for ``minutes`` (default 10; quick: 0.5; ``HAPTABLE_SOAK_MINUTES``).

    A watchdog trip (the loop stalled: e-stop) is counted with its reason; the gate is
    reset and the demo restarted, so the soak always covers the whole time."""
    from .run import start_demo

    if minutes is None:
        minutes = float(os.environ.get("HAPTABLE_SOAK_MINUTES", 0.5 if quick else 10.0))
    prof, pm = ctx.profile, ctx.pm
    res: dict = {"machine": machine_info(), "minutes": minutes, "load_avg_start": load_avg()}
    samples: list[dict] = []
    trips: list[dict] = []
    tot = {"frames": 0, "dropped_queue": 0, "dropped_camera": 0, "errors": 0, "crossings": 0}
    warm_rss = None
    last_snap: dict = {}
    with ctx.outputs(fast=False) as out:
        rss0 = rss_mb()
        t0 = time.monotonic()
        next_t = t0

        def add(snap: dict, demo: Any) -> None:
            lat = snap["latency"]
            for k in ("frames", "dropped_queue", "dropped_camera", "errors"):
                tot[k] += lat[k]
            tot["crossings"] += len(demo.crossings)

        while time.monotonic() - t0 < minutes * 60:
            run_ = start_demo("knob", prof, pm, out)
            try:
                while time.monotonic() - t0 < minutes * 60 and not run_.watchdog.tripped:
                    time.sleep(0.5)
                    now = time.monotonic()
                    if now >= next_t:
                        lat = run_.monitor.snapshot()
                        rss = rss_mb()
                        if warm_rss is None and now - t0 >= 150.0:
                            warm_rss = rss
                        samples.append(
                            {
                                "t_s": round(now - t0, 1),
                                "rss_mb": round(rss, 1),
                                "fps": lat["fps"],
                                "frames": tot["frames"] + lat["frames"],
                                "dropped_queue": tot["dropped_queue"] + lat["dropped_queue"],
                                "dropped_camera": tot["dropped_camera"] + lat["dropped_camera"],
                                "p99_processing_ms": round(lat["processing"]["p99_ms"], 2),
                                "underruns": out.status()["audio"].get("underruns"),
                                "watchdog_trips": len(trips),
                                "load_avg_1min": load_avg()[:1],
                            }
                        )
                        next_t += 30.0
            finally:
                run_.stop()
            last_snap = run_.snapshot()
            add(last_snap, run_.demo)
            if run_.watchdog.tripped:
                trips.append(
                    {"t_s": round(time.monotonic() - t0, 1), "reason": run_.watchdog.reason}
                )
                out.reset()
        ran_s = time.monotonic() - t0
        rss1 = rss_mb()
        res.update(
            {
                "ran_s": round(ran_s, 1),
                "frames": tot["frames"],
                "fps_mean": round(tot["frames"] / ran_s, 2) if ran_s else 0.0,
                "dropped_for_processing": tot["dropped_queue"],
                "dropped_by_camera_late": tot["dropped_camera"],
                "errors": tot["errors"],
                "rss_start_mb": round(rss0, 1),
                "rss_after_150s_mb": None if warm_rss is None else round(warm_rss, 1),
                "rss_end_mb": round(rss1, 1),
                "audio": _audio(out),
                "watchdog_trips": len(trips),
                "trips": trips[:20],
                "gate_estopped_at_end": out.status()["gate"].get("estopped"),
                "knob_crossings": tot["crossings"],
                "latency_last_window": {
                    k: last_snap.get("latency", {}).get(k)
                    for k in ("end_to_end", "processing", "stages")
                },
                "samples": samples,
                "note": "dropped_for_processing: frames the loop's queue discarded because "
                "processing fell behind; dropped_by_camera_late: frames the twin camera "
                "skipped because its own thread (rendering) was late. The twin keeps the last "
                "120 s of audio, so RSS grows for the first 2 minutes by design: compare "
                "rss_after_150s_mb with rss_end_mb",
            }
        )
    res["load_avg_end"] = load_avg()
    return res
