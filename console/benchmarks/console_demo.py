"""``haptable bench console-demo``: the demos started from the console, as an operator does.

The console runs headless (Textual's pilot presses the keys); the knob demo is started
from the Scenes screen and left running while the operator looks at each screen in turn
(each for one latency window: the demo reports p50/p99 over its last
``[runtime] latency_window_frames`` frames). Then the flow demo: the operator's finger is
placed on the twin (space) and moved (arrows); each move is timed from the key press to
the flow the demo scheduled under the resting finger. Every demo's output log (what the
twin's amplifier and relays received) is checked against what it reported.
"""

from __future__ import annotations

import asyncio
import json
import os
import time
from pathlib import Path

import numpy as np

#: screens the operator looks at while the knob turns, with their keys
SCREENS = (("scenes", "f6"), ("latency", "f7"), ("camera", "f2"), ("devices", "f1"))


async def _wait(pilot, cond, timeout_s: float, what: str) -> None:
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        if cond():
            return
        await pilot.pause(0.02)
    raise RuntimeError(f"{what}: not reached in {timeout_s:g} s")


async def _start(app, pilot, name: str) -> tuple[object, float]:
    """Highlight ``name`` in the demos table and press enter, as the operator does;
    (the demo's process, seconds from the key to running)."""
    await _wait(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
    await pilot.press("f6")
    await _wait(pilot, lambda: app.query("#demo-table"), 10, "scenes screen")
    await pilot.press("d")
    table = app.query_one("#demo-table")
    names = [str(table.get_row_at(i)[0]) for i in range(table.row_count)]
    table.move_cursor(row=names.index(name))
    t0 = time.monotonic()
    await pilot.press("enter")
    demos = app.session.demos
    await _wait(pilot, lambda: demos.state == "running", 120, f"{name} running")
    return app.session.demos.run, time.monotonic() - t0


async def _stop(app, pilot, run) -> dict:
    await pilot.press("f6")
    await pilot.press("s")
    await _wait(pilot, lambda: app.session.demos.name is None, 30, "demo stopped")
    await _wait(pilot, lambda: app.session.outputs is not None, 30, "outputs back")
    return run.final or {}


def _window(snap: dict) -> dict:
    lat = snap.get("latency") or {}
    audio = (snap.get("outputs") or {}).get("audio") or {}
    keep = ("n", "p50_ms", "p99_ms", "max_ms")
    return {
        "end_to_end": {k: lat.get("end_to_end", {}).get(k) for k in keep},
        "processing": {k: lat.get("processing", {}).get(k) for k in keep},
        "cpu_per_frame": {k: lat.get("cpu_per_frame", {}).get(k) for k in keep},
        "fps": lat.get("fps"),
        "dropped_queue": lat.get("dropped_queue"),
        "underruns": audio.get("underruns"),
        "underruns_audible": audio.get("underruns_audible"),
    }


def _log_matches(final: dict, snap: dict, part_s: float) -> dict:
    """The flow parts the demo reported against its output log: the piezo recording cut
    into bursts at silences, a burst of k parts' length (parts on the same patch follow
    each other without a gap) into k pieces; a part matches a piece at its frequency
    (within 1 Hz)."""
    from console.runtime.twin_log import bursts, dominant_hz

    path = final.get("twin_log")
    if not path:
        return {"checked": 0, "note": "no twin log (real outputs)"}
    data = json.loads(Path(path).read_text())
    fs = int(data["sample_rate_hz"])
    with np.load(Path(path).with_suffix(".npz")) as z:
        piezo = z["recording_v"][:, 0]
    part_n = max(1, round(part_s * fs))
    hz = []
    for b in bursts(np.stack([piezo, np.zeros_like(piezo)], axis=1), fs):
        k = max(1, round(b["n_samples"] / part_n))
        step = b["n_samples"] // k
        for j in range(k):
            a = b["start"] + j * step
            f = dominant_hz(piezo[a : a + step], fs)
            if f is not None:
                hz.append(f)
    parts = [p for e in snap.get("flow", {}).get("last", []) for p in e.get("parts", [])]
    freq_ok = sum(any(abs(h - p["frequency_hz"]) <= 1.0 for h in hz) for p in parts)
    return {"parts_reported": len(parts), "parts_with_a_burst_at_their_hz": freq_ok}


async def _scenario(ctx, seconds: float, flow_moves: int) -> dict:
    from console.tui.app import HapTableApp

    app = HapTableApp(ctx, fast=False, initial="devices")
    out: dict = {}
    async with app.run_test(size=(120, 40)) as pilot:
        run, t_start = await _start(app, pilot, "knob")
        knob = {"start_s": round(t_start, 3), "screens": {}}
        for screen, key in SCREENS:
            await pilot.press(key)
            await pilot.pause(seconds)
            knob["screens"][screen] = _window(run.snapshot())
        final = await _stop(app, pilot, run)
        knob["crossings"] = (final.get("final") or {}).get("knob", {}).get("crossings")
        out["knob"] = knob
        if flow_moves:
            out["flow"] = await _flow(app, pilot, flow_moves)
    return out


async def _flow(app, pilot, moves: int) -> dict:
    app.session.demos.params = {"flow": {"prepare": False}}
    run, t_start = await _start(app, pilot, "flow")
    await pilot.press("space")  # the operator's finger replaces the scripted hand
    delays, missed = [], 0
    for k in range(moves):
        await _wait(pilot, lambda: not run.snapshot()["outputs"]["busy"], 30, "flow over")
        n0 = run.snapshot()["flow"]["flows"]
        t0 = time.monotonic()
        await pilot.press("down" if k % 2 == 0 else "up")
        try:
            await _wait(pilot, lambda n=n0: run.snapshot()["flow"]["flows"] > n, 10, "flow")
            delays.append(time.monotonic() - t0)
        except RuntimeError:
            missed += 1
    await _wait(pilot, lambda: not run.snapshot()["outputs"]["busy"], 30, "flow over")
    snap = run.snapshot()
    window = _window(snap)
    final = await _stop(app, pilot, run)
    from console.bench import summarize_s

    return {
        "start_s": round(t_start, 3),
        "moves": moves,
        "missed": missed,
        "key_to_flow_scheduled": summarize_s(delays) if delays else None,
        "still_ms": app.ctx.profile.get("demos.still_ms"),
        "loop": window,
        "output_log": _log_matches(final, snap, float(app.ctx.profile.get("vibrotactile.part_s"))),
    }


def run(ctx, quick: bool) -> dict:
    """Knob from the console for one latency window per screen; flow with the
    operator's finger moved ``moves`` times."""
    from console.bench import machine_info

    seconds = 21.0  # one latency window (1200 frames at 60 fps) per screen
    load0 = os.getloadavg()
    got = asyncio.run(_scenario(ctx, seconds, 4 if quick else 10))
    p99 = [w["processing"]["p99_ms"] for w in got["knob"]["screens"].values()]
    return {
        **got,
        "seconds_per_screen": seconds,
        "target_p99_ms": 5.0,
        "worst_screen_p99_processing_ms": max(p99),
        "meets_target": max(p99) < 5.0,
        "load_avg_start": load0,
        "load_avg_end": os.getloadavg(),
        "machine": machine_info(),
    }
