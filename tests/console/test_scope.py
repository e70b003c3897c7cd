"""The scope tap: the gate's last blocks per channel, as the driver got them."""

from __future__ import annotations

import numpy as np
import pytest

from console.kernel.scheduler import Scheduler
from console.safety import Limits, SafetyGate
from console.safety.scope import ScopeTap
from console.signals.stimuli import make_stimulus

FS = 48000


def test_the_ring_keeps_the_newest_blocks_with_their_clock_and_volts():
    rng = np.random.default_rng(3)
    tap = ScopeTap(FS, ("piezo", "screen"), (150.0, 300.0), seconds=0.01)  # 480 rows
    blocks, clock = [], 1000
    tap_clock0 = clock
    for _ in range(40):
        n = int(rng.integers(1, 200))
        b = rng.uniform(-1, 1, (n, 2)).astype(np.float32)
        tap.write(b, clock)
        blocks.append(b)
        clock += n
    every = np.concatenate(blocks).astype(np.float64) * [150.0, 300.0]
    whole = tap.read(None)
    assert whole.n == tap.capacity == 480
    np.testing.assert_array_equal(whole.volts, every[-480:])
    assert whole.clock == clock - 480 and whole.clock + whole.n == clock
    part = tap.read(0.001)  # 48 rows
    np.testing.assert_array_equal(part.volts, every[-48:])
    assert part.clock == clock - 48
    assert part.peak_v()["screen"] == pytest.approx(np.abs(every[-48:, 1]).max())
    assert part.t_ms()[-1] == 0.0 and part.t_ms()[0] == pytest.approx(-47 / 48)
    # a block longer than the ring keeps its end, clocked
    long = rng.uniform(-1, 1, (1000, 2)).astype(np.float32)
    tap.write(long, clock)
    got = tap.read(None)
    np.testing.assert_array_equal(got.volts, long[-480:].astype(np.float64) * [150.0, 300.0])
    assert got.clock == clock + 1000 - 480
    assert tap_clock0 < got.clock


def test_an_empty_tap_reads_nothing():
    tap = ScopeTap(FS, ("piezo", "screen"), (1.0, 1.0))
    trace = tap.read(0.05)
    assert trace.n == 0 and trace.peak_v() == {"piezo": 0.0, "screen": 0.0}


def test_the_scope_equals_what_the_twin_amplifiers_received(outputs):
    """Through a kernel client: the scope the kernel's gate keeps, as a process reads it."""
    outputs.play(make_stimulus("sine-PA", FS))
    trace = outputs.scope(None)
    rec = outputs.recording()
    n = min(trace.n, rec.shape[0])
    assert n > FS  # the whole 1 s tone is in the ring
    np.testing.assert_allclose(trace.volts[-n:], rec[-n:], atol=1e-4)
    assert trace.clock + trace.n == outputs.status()["gate"]["clock"]
    assert trace.channels == ("piezo", "screen")
    peaks = trace.peak_v()
    assert peaks["piezo"] == pytest.approx(20.0, rel=1e-3) and peaks["screen"] == 0.0


class MemoryBoard:
    def __init__(self, channels: int = 8) -> None:
        self.channels = channels
        self.closed = [False] * channels

    def set(self, channel: int, closed: bool) -> None:
        self.closed[channel - 1] = closed

    def states(self) -> list[bool]:
        return list(self.closed)

    def status(self) -> dict:
        return {}

    def close(self) -> None:
        pass


def test_an_estop_ramp_reaches_zero_at_the_slew_limit_in_the_scope(profile):
    """Driven block by block (no driver thread): e-stop mid-tone, the trace shows the
    level then and a ramp as long as the slew limit allows (level / slew rate)."""
    limits = Limits.from_profile(profile)
    relay_channels = {n: p["relay_channel"] for n, p in profile.items("patches").items()}
    gate = SafetyGate(limits, MemoryBoard(), relay_channels=relay_channels, screen_channel=8)
    sched = Scheduler(gate, relay_channels=relay_channels, screen_channel=8)
    out = np.zeros((64, 2), np.float32)
    try:
        sched.play(sched.check(make_stimulus("sine-PA", FS)))
        for _ in range(100000):
            gate.fill(out)
            if abs(gate.level_v[0]) > 15.0 and gate.clock > FS // 4:
                break
        level = abs(gate.level_v[0])
        gate.estop("test", wait=False)
        estop_clock = gate.events[-1].clock
        for _ in range(200):
            gate.fill(out)
        gate.wait_safe(5)
    finally:
        sched.close()
    trace = gate.scope.read(0.5)
    start_v, ramp_ms = trace.silent_after(estop_clock)
    assert start_v == pytest.approx(level, rel=1e-5)
    expect_ms = level / limits.slew_v_per_s("piezo", frozenset({"PA"})) * 1e3
    assert abs(ramp_ms - expect_ms) <= 1e3 / FS + 1e-9
    k = estop_clock - trace.clock
    ramp = np.abs(trace.volts[k:, 0])
    assert np.all(np.diff(ramp) <= 1e-4)  # only ever down
    assert level - 1e-4 <= trace.peak_v()["piezo"] <= 20.0 + 1e-4
    assert trace.peak_v()["screen"] == 0.0
