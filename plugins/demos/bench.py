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
            _run_for(run_, max(seconds, 12.0))
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
    """The knob demo for ``minutes`` (default 10; quick: 0.5; ``HAPTABLE_SOAK_MINUTES``)."""
    from .run import start_demo

    if minutes is None:
        minutes = float(os.environ.get("HAPTABLE_SOAK_MINUTES", 0.5 if quick else 10.0))
    prof, pm = ctx.profile, ctx.pm
    res: dict = {"machine": machine_info(), "minutes": minutes, "load_avg_start": load_avg()}
    samples = []
    with ctx.outputs(fast=False) as out:
        rss0 = rss_mb()
        with start_demo("knob", prof, pm, out) as run_:
            t0 = time.monotonic()
            next_t = t0
            while time.monotonic() - t0 < minutes * 60:
                time.sleep(0.5)
                if time.monotonic() >= next_t:
                    lat = run_.monitor.snapshot()
                    samples.append(
                        {
                            "t_s": round(time.monotonic() - t0, 1),
                            "rss_mb": round(rss_mb(), 1),
                            "fps": lat["fps"],
                            "frames": lat["frames"],
                            "dropped_queue": lat["dropped_queue"],
                            "dropped_camera": lat["dropped_camera"],
                            "p99_processing_ms": round(lat["processing"]["p99_ms"], 2),
                            "underruns": out.status()["audio"].get("underruns"),
                            "load_avg": load_avg()[:1],
                        }
                    )
                    next_t += 30.0
                if run_.watchdog.tripped:
                    break
            run_.stop()
            snap = run_.snapshot()
            crossings = len(run_.demo.crossings)
        rss1 = rss_mb()
        res.update(
            {
                "ran_s": round(snap["uptime_s"], 1),
                "frames": snap["latency"]["frames"],
                "fps": snap["latency"]["fps"],
                "dropped_for_processing": snap["latency"]["dropped_queue"],
                "dropped_by_camera_late": snap["latency"]["dropped_camera"],
                "errors": snap["latency"]["errors"],
                "rss_start_mb": round(rss0, 1),
                "rss_end_mb": round(rss1, 1),
                "audio": _audio(out),
                "watchdog": snap["watchdog"],
                "gate_estopped": out.status()["gate"].get("estopped"),
                "knob_crossings": crossings,
                "latency_last_window": {
                    "end_to_end": snap["latency"]["end_to_end"],
                    "processing": snap["latency"]["processing"],
                    "stages": snap["latency"]["stages"],
                },
                "samples": samples,
                "note": "the twin records the last 120 s of audio, so RSS grows for the first "
                "2 minutes by design; compare samples after that",
            }
        )
    res["load_avg_end"] = load_avg()
    return res
