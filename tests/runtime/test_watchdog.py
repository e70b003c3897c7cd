"""The watchdog silences the outputs (gate e-stop with a clear reason) on a stall."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from console.core.types import Frame
from console.runtime.loop import FrameLoop
from console.runtime.watchdog import Watchdog, stall_reason


class Stuck:
    def __init__(self, stuck_s: float, where: str = "stage 'vision'") -> None:
        self.stuck_s, self.where = stuck_s, where

    def stall(self, now_s=None):
        return self.stuck_s, self.where


def test_trips_once_past_the_limit_with_a_reason_naming_where():
    calls: list[str] = []
    target = Stuck(0.1)
    wd = Watchdog(target, calls.append, limit_s=0.25)
    assert not wd.check(0.0)
    target.stuck_s = 0.4
    assert wd.check(0.0)
    assert not wd.check(0.0)  # latched: one e-stop, not one per check
    assert len(calls) == 1
    assert "stage 'vision'" in calls[0] and "400 ms" in calls[0] and "watchdog_ms" in calls[0]
    wd.reset()
    assert wd.check(0.0) and len(calls) == 2


def test_limit_must_be_positive():
    with pytest.raises(ValueError):
        Watchdog(Stuck(0), print, 0.0)


def test_a_failing_action_does_not_kill_the_watchdog():
    def boom(reason):
        raise RuntimeError("x")

    wd = Watchdog(Stuck(1.0), boom, 0.1)
    assert wd.check(0.0) and wd.tripped


def test_reason_for_a_dead_thread():
    assert "forever" in stall_reason(float("inf"), "a loop thread died", 0.25, (0.5, 2))


def test_reason_names_an_overloaded_machine_and_only_then():
    busy = stall_reason(0.31, "stage 'vision'", 0.25, (20.4, 2))
    assert "310 ms in stage 'vision'" in busy
    assert "overloaded (load average 20.4 on 2 cores): close other programs" in busy
    assert "overloaded" not in stall_reason(0.31, "stage 'vision'", 0.25, (1.5, 2))


class OneFrameCamera:
    def __init__(self) -> None:
        self.sent = False

    def read(self, timeout_s=0.1):
        if self.sent:
            threading.Event().wait(timeout_s)
            return None
        self.sent = True
        return Frame(np.zeros((4, 4), np.uint8), 0, 0.0)

    def close(self):
        pass

    def status(self):
        return {}


def test_loop_reports_where_it_is_stuck():
    release = threading.Event()
    entered = threading.Event()

    def hang(f, work):
        entered.set()
        release.wait(5)

    loop = FrameLoop(OneFrameCamera(), [("vision", lambda f, w: None), ("effect", hang)]).start()
    try:
        assert entered.wait(5)
        stuck, where = loop.stall()
        assert where == "stage 'effect'" and stuck >= 0
    finally:
        release.set()
        loop.stop()
    stuck, where = loop.stall()
    assert where == "camera (no frame arriving)"


class Carrier:
    """A live stream as a client describes it: a 200 Hz sine of 40 V on the screen channel,
    ramped in by the kernel's synth, never ending (its targets posted once it is bound)."""

    def __init__(self) -> None:
        from console.signals.stream_synth import StreamSpec

        self.spec = StreamSpec(
            sample_rate_hz=48000,
            patches=frozenset(),
            screen=True,
            carrier_max_v=40.0,
            carrier_min_hz=60,
            carrier_max_hz=400,
            start_hz=200,
            glide_ms=10,
            ramp_ms=100,
        )
        self.sink = None

    def bind(self, sink) -> None:
        self.sink = sink
        sink.post(carrier_hz=200.0, carrier_v=40.0)


def test_a_stalled_loop_silences_a_playing_stream(profile, plugins):
    from console.kernel.client import open_outputs

    release = threading.Event()
    entered = threading.Event()

    def hang(f, work):
        entered.set()
        release.wait(10)

    with open_outputs(profile, plugins, fast=False) as out:
        src = Carrier()
        report = out.stream(src, name="carrier")
        assert src.sink is not None
        loop = FrameLoop(OneFrameCamera(), [("effect", hang)]).start()
        wd = Watchdog(loop, out.estop, limit_s=0.15).start()
        try:
            assert entered.wait(5)
            assert report.done.wait(10)  # the e-stop ended the stream
        finally:
            release.set()
            wd.stop()
            loop.stop()
        st = out.status()["gate"]
        assert st["estopped"]
        assert "watchdog" in st["estop_reason"] and "'effect'" in st["estop_reason"]
        rec = out.recording()
        assert np.abs(rec[:, 1]).max() > 10.0  # the carrier did play
        # after the e-stop, every sample is silent and the screen relay is open
        blocks_after = out.status()["audio"]["blocks"]
        threading.Event().wait(0.05)
        rec2 = out.recording()
        assert np.all(rec2[-(out.status()["audio"]["blocks"] - blocks_after) * 64 - 64 :] == 0.0)
        assert 5 not in out.relay_state()
