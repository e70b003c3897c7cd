"""Benchmarks of the interaction loop on the profile's devices (the twin by default).

``loop``: the knob and flow demos at the camera's rate, audio paced in real time with
the profile's blocks; per-stage and end-to-end (frame arrival -> first output sample
scheduled) p50/p99. ``soak``: the knob demo for minutes; frames dropped for processing
reasons, RSS at start and end, audio underruns, watchdog trips.
"""

from __future__ import annotations

import os
import sys
import time
from typing import Any

from console.plugin_api import Frame, machine_info, summarize_s, support_priority
from console.plugin_api.runtime import (
    DEQUEUED,
    PROCESSING,
    finish_probe,
    open_camera,
    open_outputs,
    start_probe,
)

from .run import start_demo
from .script import script_twin

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


def rss_after_trim_mb() -> float | None:
    """RSS after glibc's ``malloc_trim(0)`` returned free heap pages (None elsewhere)."""
    try:
        import ctypes

        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        return None
    return round(rss_mb(), 2)


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
        "underruns_audible": a.get("underruns_audible"),
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
        "cpu_per_frame": lat["cpu_per_frame"],
        "cpu_stages": lat["cpu_stages"],
        "capture_to_arrival": lat["capture_to_arrival"],
        "watchdog": snap["watchdog"],
    }


class ReplayCamera:
    """Frames rendered beforehand by the camera twin, replayed at ``fps`` in a loop.

    The lab's camera delivers frames without costing the console's CPU; the twin renders
    them in-process. Replaying pre-rendered frames measures the loop's processing alone.
    """

    def __init__(self, images: list, background, fps: float = 60.0) -> None:
        self.images, self._bg, self.fps = images, background, float(fps)
        self._k = 0
        self._t0: float | None = None
        self._dropped = 0
        self._closed = False

    def read(self, timeout_s: float = 0.1):
        if self._closed:
            return None
        now = time.monotonic()
        if self._t0 is None:
            self._t0 = now
        due = self._t0 + self._k / self.fps
        if due - now > timeout_s:
            time.sleep(timeout_s)
            return None
        if due > now:
            time.sleep(due - now)
        elif now - due >= 1.0 / self.fps:  # late: those frames were lost
            missed = int((now - due) * self.fps)
            self._dropped += missed
            self._k += missed
            due = self._t0 + self._k / self.fps
        k = self._k
        self._k += 1
        return Frame(self.images[k % len(self.images)], k, due, source="replay")

    def background(self):
        return self._bg

    def close(self) -> None:
        self._closed = True

    def status(self) -> dict:
        return {"driver": "replay", "dropped": self._dropped, "frames": self._k}


def render_script(ctx: Any, demo: str, seconds: float) -> ReplayCamera:
    """The twin camera performing ``demo``'s script, rendered ahead of time."""
    cam = open_camera(ctx.profile, ctx.pm)
    try:
        cam.realtime = False
        script_twin(cam, demo, ctx.profile)
        fps = float(ctx.profile.get("camera.fps") or 60.0)
        images = [cam.read().image for _ in range(int(seconds * fps))]
        bg = cam.background()
    finally:
        cam.close()
    return ReplayCamera(images, bg, fps)


def _over_limit(run_, limit_ms: float) -> dict:
    """Frames (in the monitor's window) whose processing took longer than the watchdog
    limit: each would have e-stopped the outputs."""
    vals = run_.monitor.values_s(PROCESSING) * 1e3
    return {"limit_ms": limit_ms, "frames_over": int((vals > limit_ms).sum()), "of": int(vals.size)}


class DecisionFrames:
    """A frame sink timing each frame with a hand from the start of its processing to the
    end of its ``classify`` stage (vision + gestures: the ``dequeued`` and ``classify``
    stamps), the frames on which the classifier's model decided a placement's gesture
    (``work["named"]``) apart from the others."""

    def __init__(self) -> None:
        self.decision_s: list[float] = []
        self.other_s: list[float] = []

    def __call__(self, frame: Any, work: dict) -> None:
        st = frame.stamps_s
        if work.get("hand") is None or "classify" not in st or DEQUEUED not in st:
            return
        dt = st["classify"] - st[DEQUEUED]
        (self.decision_s if "named" in work else self.other_s).append(dt)

    def summary(self) -> dict:
        return {
            "decision_frames": summarize_s(self.decision_s),
            "other_frames_with_hand": summarize_s(self.other_s),
            "means": "dequeued -> classify stamps (vision + classify) of each frame with "
            "a hand; decision frames: the model named the placement's gesture on them",
        }


def _measure(ctx: Any, demo: str, seconds: float, camera: Any = None, **kw: Any) -> dict:
    prof, pm = ctx.profile, ctx.pm
    limit = float(prof.get("runtime.watchdog_ms") or 250.0)
    decisions = DecisionFrames()
    with ctx.outputs(fast=False) as out:
        # the benchmark measures latency: a stall is counted, not acted on
        with start_demo(
            demo,
            prof,
            pm,
            out,
            camera=camera,
            script=camera is None,
            watchdog_ms=1e9,
            sinks=[decisions],
            **kw,
        ) as run_:
            _run_for(run_, seconds)
            run_.stop()
            res = _latency_summary(run_.snapshot())
            res["vision_and_classify"] = decisions.summary()
            res["would_trip_watchdog"] = _over_limit(run_, limit)
            if demo == "knob":
                res["crossings"] = run_.demo.crossings_total
            else:
                flows = [e for e in run_.demo.events if e.get("kind") == "flow"]
                res["flows"] = len(flows)
                res["trigger_to_scheduled_cached"] = summarize_s(
                    [e["t_scheduled_s"] - e["t_arrival_s"] for e in flows if e["late_s"] == 0.0]
                )
                res["plan_compute_when_not_cached"] = summarize_s(
                    [e["late_s"] for e in flows if e["late_s"] > 0.0]
                )
        res["audio"] = _audio(out)
    return res


def run_loop(ctx: Any, quick: bool) -> dict:
    with support_priority() as rt:  # as the console's demo process serves its loop
        res = _run_loop(ctx, quick)
    res["support_threads_realtime"] = rt
    return res


def _run_loop(ctx: Any, quick: bool) -> dict:
    seconds = 8.0 if quick else 30.0
    prof = ctx.profile
    res: dict = {
        "machine": machine_info(),
        "load_avg_start": load_avg(),
        "camera_fps": prof.get("camera.fps"),
        "target": {"p99_processing_ms": TARGET_P99_MS, "fps": 60, "block": 64, "rate_hz": 48000},
        "seconds_per_run": seconds,
        "end_to_end_means": "frame arrival (taken from the camera) -> the frame's output handed "
        "to the scheduler (knob: posted to the live stream, played from its next audio block, "
        "at most one block later; flow: the plan queued)",
        "replay_means": "frames rendered by the twin beforehand and replayed at the camera "
        "rate: the loop's processing without the twin's rendering on the same CPU (as in the "
        "lab, where the camera renders nothing)",
    }
    for demo in ("knob", "flow"):
        t = seconds if demo == "knob" else max(seconds, 16.0)
        cam = render_script(ctx, demo, 2.0 if demo == "knob" else 5.0)
        res[f"{demo}_replay"] = _measure(ctx, demo, t, camera=cam, prepare=False)
        res[f"{demo}_live_twin"] = _measure(ctx, demo, t, prepare=False)
    k = res["knob_replay"]
    res["p99_processing_ms"] = k["processing"]["p99_ms"]
    res["p99_cpu_per_frame_ms"] = k["cpu_per_frame"]["p99_ms"]
    res["meets_target"] = bool(k["processing"]["p99_ms"] < TARGET_P99_MS)
    res["meets_target_cpu"] = bool(k["cpu_per_frame"]["p99_ms"] < TARGET_P99_MS)
    res["load_avg_end"] = load_avg()
    return res


#: The soak's RSS baseline is taken after this warm-up: imports, first frames, caches, and
#: the live logs (512 entries each: knob crossings fill theirs in about 70 s of turning).
SOAK_WARMUP_S = 90.0
#: RSS and counters are sampled every 10 s from here on (the warm-up is shown too).
SOAK_SAMPLES_FROM_S = 10.0
#: Seconds of audio the twin keeps during a soak (its recording is a bounded ring; a short
#: one is filled during the warm-up, so the RSS after it shows only real growth).
SOAK_RECORD_S = 5.0


def soak_profile(profile: Any) -> Any:
    """The profile with the twin's recording shortened to ``SOAK_RECORD_S``."""
    import dataclasses

    data = dict(profile.data)
    data["twin_audio"] = {**dict(data.get("twin_audio") or {}), "record_s": SOAK_RECORD_S}
    return dataclasses.replace(profile, data=data)


def rss_slope_mb_per_min(samples: list[dict], from_s: float) -> float | None:
    """Least-squares slope of RSS over time (MB/min) for the samples from ``from_s``."""
    import numpy as np

    pts = [(x["t_s"], x["rss_mb"]) for x in samples if x["t_s"] >= from_s]
    if len(pts) < 2:
        return None
    t, r = np.array(pts).T
    return float(np.polyfit(t / 60.0, r, 1)[0])


def run_soak(ctx: Any, quick: bool, minutes: float | None = None) -> dict:
    """The knob demo for ``minutes`` (default 10; quick: 0.5; ``HAPTABLE_SOAK_MINUTES``).

    A watchdog trip (the loop stalled: e-stop) is counted with its reason; the gate is
    reset and the demo restarted, so the soak always covers the whole time. RSS is taken
    after ``SOAK_WARMUP_S`` and at the end, with a least-squares slope (MB/min) between.
    The polling thread runs as the console's demo process runs its status thread."""
    with support_priority() as rt:
        res = _run_soak(ctx, quick, minutes)
    res["support_threads_realtime"] = rt
    return res


def _twin(profile: Any, pm: Any) -> bool:
    """The profile's audio output and relay board are the twin's (their probes say so)."""
    return pm.simulated("audio_output", profile) and pm.simulated("relay_board", profile)


def _run_soak(ctx: Any, quick: bool, minutes: float | None = None) -> dict:

    if minutes is None:
        minutes = float(os.environ.get("HAPTABLE_SOAK_MINUTES", 0.5 if quick else 10.0))
    prof, pm = soak_profile(ctx.profile), ctx.pm
    warmup_s = min(SOAK_WARMUP_S, minutes * 60 / 3)  # a short soak: its first third
    res: dict = {"machine": machine_info(), "minutes": minutes, "load_avg_start": load_avg()}
    samples: list[dict] = []
    trips: list[dict] = []
    tot = {"frames": 0, "dropped_queue": 0, "dropped_camera": 0, "errors": 0, "crossings": 0}
    warm_rss = None
    last_snap: dict = {}
    private = _twin(prof, pm)  # its own table: it may reset its watchdog's e-stops there
    with open_outputs(prof, pm, fast=False, private=private) as out:
        rss0 = rss_mb()
        a = out.status()["audio"]
        period_s = a["block_size"] / a["sample_rate_hz"]
        slack_s = (int(a.get("buffer_periods") or 2) - 1) * period_s
        probe = start_probe(minutes * 60, period_s, slack_s)
        t0 = time.monotonic()
        next_t = t0 + SOAK_SAMPLES_FROM_S

        def add(snap: dict, demo: Any) -> None:
            lat = snap["latency"]
            for k in ("frames", "dropped_queue", "dropped_camera", "errors"):
                tot[k] += lat[k]
            tot["crossings"] += demo.crossings_total

        while time.monotonic() - t0 < minutes * 60:
            run_ = start_demo("knob", prof, pm, out)
            try:
                while time.monotonic() - t0 < minutes * 60 and not run_.watchdog.tripped:
                    time.sleep(0.25)
                    now = time.monotonic()
                    if now >= next_t:
                        lat = run_.monitor.snapshot()
                        rss = rss_mb()
                        if warm_rss is None and now - t0 >= warmup_s:
                            warm_rss = rss
                        a = out.status()["audio"]
                        samples.append(
                            {
                                "t_s": round(now - t0, 1),
                                "rss_mb": round(rss, 2),
                                "fps": lat["fps"],
                                "frames": tot["frames"] + lat["frames"],
                                "dropped_queue": tot["dropped_queue"] + lat["dropped_queue"],
                                "dropped_camera": tot["dropped_camera"] + lat["dropped_camera"],
                                "p99_processing_ms": round(lat["processing"]["p99_ms"], 2),
                                "p99_cpu_per_frame_ms": round(lat["cpu_per_frame"]["p99_ms"], 2),
                                "underruns": a.get("underruns"),
                                "blocks": a.get("blocks"),
                                "watchdog_trips": len(trips),
                                "load_avg_1min": load_avg()[:1],
                            }
                        )
                        next_t += 10.0
            finally:
                run_.stop()
            last_snap = run_.snapshot()
            add(last_snap, run_.demo)
            if run_.watchdog.tripped:
                trips.append(
                    {"t_s": round(time.monotonic() - t0, 1), "reason": run_.watchdog.reason}
                )
                if not private:  # an operator's table: only an operator resets it
                    break
                out.wait_safe(5.0)
                out.reset("the soak on its own twin table")
        ran_s = time.monotonic() - t0
        jitter = finish_probe(probe)
        rss1 = rss_mb()
        rss1_trim = rss_after_trim_mb()
        audio = _audio(out)
        audio["buffer_periods"] = out.status()["audio"].get("buffer_periods")
        audio["latency_ms"] = 1e3 * (out.status()["audio"].get("latency_s") or 0.0)
        res.update(
            {
                "ran_s": round(ran_s, 1),
                "frames": tot["frames"],
                "fps_mean": round(tot["frames"] / ran_s, 2) if ran_s else 0.0,
                "dropped_for_processing": tot["dropped_queue"],
                "dropped_by_camera_late": tot["dropped_camera"],
                "errors": tot["errors"],
                "rss_at_open_mb": round(rss0, 1),
                "warmup_s": warmup_s,
                "rss_start_mb": None if warm_rss is None else round(warm_rss, 2),
                "rss_end_mb": round(rss1, 2),
                "rss_slope_mb_per_min": rss_slope_mb_per_min(samples, warmup_s),
                "rss_end_after_malloc_trim_mb": rss1_trim,
                "switch_interval_ms": round(sys.getswitchinterval() * 1e3, 3),
                "memory_locked": out.status()["memory_locked"],
                "audio": audio,
                "machine_jitter": jitter,
                "twin_record_s": SOAK_RECORD_S,
                "twin_camera_process": bool(prof.get("runtime.twin_camera_process")),
                "watchdog_trips": len(trips),
                "trips": trips[:20],
                "gate_estopped_at_end": out.status()["gate"].get("estopped"),
                "knob_crossings": tot["crossings"],
                "latency_last_window": {
                    k: last_snap.get("latency", {}).get(k)
                    for k in ("end_to_end", "processing", "cpu_per_frame", "stages", "cpu_stages")
                },
                "samples": samples,
                "note": "dropped_for_processing: frames the loop's queue discarded because "
                "processing fell behind; dropped_by_camera_late: frames the twin camera "
                "skipped because its rendering was late, or (twin camera in its own process) "
                "that the loop's camera thread read too late to take. rss_start_mb is taken "
                f"after {warmup_s:g} s of warm-up (the twin keeps {SOAK_RECORD_S:g} s of "
                "audio during a soak and the live logs 512 entries, filled by then); the "
                "slope is fitted from there on; samples start at "
                f"{SOAK_SAMPLES_FROM_S:g} s. "
                "underruns: the twin DAC found its device buffer (buffer_periods blocks) "
                "empty; underruns_audible: of those, the ones that cut into sound (the block "
                "played before the gap was not silent). rss_end_after_malloc_trim_mb: RSS "
                "once glibc returned its free heap (growth it gives back is allocator retention, not a leak). machine_jitter: "
                "a real-time thread in a separate small process woken every audio block "
                "during the soak (console.runtime.jitter); late_over_slack counts the wakes "
                "that would have emptied the device buffer: the machine's share of underruns",
            }
        )
    res["load_avg_end"] = load_avg()
    return res
