"""``haptable bench gate-fill``: the work the audio callback does, block by block.

The profile's safety gate and output scheduler (the kernel's, ``console.kernel``) are
built around an in-memory relay board (no driver: nothing plays anywhere) and ``gate.fill(out)`` is called back to back,
as a fast-forward driver would, timing each call: while idle (no plan), while a plan
plays (the ``sine-PALL`` stimulus: 250 Hz, 20 V peak on every patch, relays switching
before and after), and while an e-stop ramps a playing plan down. Medians and p99 per
phase, in microseconds, and the block's own period for scale.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from console.core.bench_stats import machine_info
from console.kernel.scheduler import Scheduler
from console.safety import Limits, SafetyGate
from console.signals.stimuli import make_stimulus


class _MemoryBoard:
    """A relay board in memory: what the gate switches, nothing else."""

    def __init__(self, channels: int) -> None:
        self.channels = channels
        self._closed = [False] * channels

    def set(self, channel: int, closed: bool) -> None:
        self._closed[channel - 1] = bool(closed)

    def states(self) -> list[bool]:
        return list(self._closed)

    def status(self) -> dict[str, Any]:
        return {"driver": "memory", "closed": self.states()}

    def close(self) -> None:
        self._closed = [False] * self.channels


def _stats_us(samples_s: list[float]) -> dict[str, float]:
    a = np.asarray(samples_s, float) * 1e6
    if a.size == 0:
        return {"n": 0, "p50_us": float("nan"), "p99_us": float("nan"), "max_us": float("nan")}
    return {
        "n": int(a.size),
        "p50_us": float(np.percentile(a, 50)),
        "p99_us": float(np.percentile(a, 99)),
        "max_us": float(a.max()),
    }


def run(ctx: Any, quick: bool, rounds: int | None = None) -> dict[str, Any]:
    profile = ctx.profile
    limits = Limits.from_profile(profile)
    block = int(profile.get("audio.block_size"))
    fs = int(profile.get("audio.sample_rate_hz"))
    relay_channels = {  # 0: a patch on a channel of its own without a relay
        n: p["relay_channel"] for n, p in profile.items("patches").items() if p["relay_channel"]
    }
    screen_channel = int(profile.get("screen.relay_channel"))
    board = _MemoryBoard(int(profile.get("relays.channels")))
    gate = SafetyGate(
        limits,
        board,
        relay_channels=relay_channels,
        screen_channel=screen_channel,
        latency_samples=block,
    )
    sched = Scheduler(gate, relay_channels=relay_channels, screen_channel=screen_channel)
    out = np.zeros((block, limits.layout.n), np.float32)  # a column per [audio] channels name
    times: dict[str, list[float]] = {"idle": [], "playing": [], "estop_ramp": []}
    rounds = rounds if rounds is not None else (2 if quick else 8)
    plan = sched.check(make_stimulus("sine-PALL", fs))  # checked once, played each round

    def tick(phase: str) -> None:
        t0 = time.perf_counter()
        gate.fill(out)
        times[phase].append(time.perf_counter() - t0)

    try:
        for r in range(rounds):
            for _ in range(2000):
                tick("idle")
            report = sched.play(plan)
            # the relay switch runs on the scheduler's thread; keep the clock going
            deadline = time.monotonic() + 30
            while not report.done.is_set() and time.monotonic() < deadline:
                tick("playing" if any(gate.level_v) else "idle")
            if report.error:
                raise RuntimeError(f"bench plan refused: {report.error}")
            if r % 2 == 0:  # every other round: an e-stop in the middle of a plan
                report = sched.play(plan)
                while not any(gate.level_v) and time.monotonic() < deadline:
                    tick("idle")
                for _ in range(block and fs // (4 * block)):
                    tick("playing")
                gate.estop("bench", wait=False)
                while any(gate.level_v):
                    tick("estop_ramp")
                for _ in range(200):
                    tick("idle")
                gate.wait_safe(5)
                gate.reset()  # the scheduler stays the gate's source
    finally:
        sched.close()
    return {
        "profile": profile.name,
        "block_size": block,
        "sample_rate_hz": fs,
        "channels": list(limits.channels),
        "block_period_us": 1e6 * block / fs,
        "fill": {phase: _stats_us(v) for phase, v in times.items()},
        "machine": machine_info(),
    }
