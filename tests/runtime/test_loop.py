"""The frame loop: drop-oldest queue, per-stage stamps, latency monitor, failures."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from console.core.types import Frame
from console.runtime.latency import (
    ARRIVAL,
    LatencyMonitor,
    Ring,
    percentiles_ms,
    stage_durations_s,
)
from console.runtime.loop import FrameLoop, FrameQueue


def frame(seq: int, **stamps: float) -> Frame:
    f = Frame(np.zeros((4, 4), np.uint8), seq, 0.0)
    for k, v in stamps.items():
        f.stamp(k, v)
    return f


class ListCamera:
    """Hands out a fixed number of frames, then nothing."""

    def __init__(self, n: int) -> None:
        self.n, self.k = n, 0
        self.lock = threading.Lock()

    def read(self, timeout_s: float = 0.1):
        with self.lock:
            if self.k >= self.n:
                threading.Event().wait(timeout_s)
                return None
            self.k += 1
            return Frame(np.zeros((4, 4), np.uint8), self.k - 1, 0.0)

    def close(self) -> None:
        pass

    def status(self) -> dict:
        return {"dropped": 0}


def test_queue_drops_the_oldest_and_never_blocks():
    q = FrameQueue(2)
    assert q.put(1) is None and q.put(2) is None
    assert q.put(3) == 1  # full: the oldest goes
    assert q.put(4) == 2
    assert [q.get(0), q.get(0)] == [3, 4]
    assert q.get(0.01) is None
    q.close()
    assert q.get(None) is None  # closed: returns at once


def test_queue_size_must_be_positive():
    with pytest.raises(ValueError):
        FrameQueue(0)


def test_ring_keeps_the_last_samples():
    r = Ring(3)
    for x in range(5):
        r.add(float(x))
    assert sorted(r.values()) == [2.0, 3.0, 4.0]
    assert r.count == 5


def test_stage_durations_skip_stages_a_frame_did_not_reach():
    st = {ARRIVAL: 1.0, "vision": 1.004, "effect": 1.010}
    d = stage_durations_s(st, [ARRIVAL, "vision", "classify", "effect", "scheduled"])
    assert d == pytest.approx({"vision": 0.004, "effect": 0.006})
    assert sum(d.values()) == pytest.approx(0.010)


def test_percentiles_match_numpy_and_empty_is_nan():
    x = np.random.default_rng(1).exponential(0.003, 500)
    p = percentiles_ms(x)
    assert p["p50_ms"] == pytest.approx(np.percentile(x, 50) * 1e3)
    assert p["p99_ms"] == pytest.approx(np.percentile(x, 99) * 1e3)
    assert p["n"] == 500
    assert np.isnan(percentiles_ms(np.array([]))["p99_ms"])


def test_monitor_end_to_end_counts_only_frames_that_reached_the_end_stage():
    m = LatencyMonitor(["vision", "scheduled", "scene"], end_stage="scheduled")
    m.record(frame(0, arrival=0.0, dequeued=0.0005, vision=0.002, scheduled=0.003, scene=0.0031))
    m.record(frame(1, arrival=1.0, dequeued=1.001, vision=1.004))  # no hand: ends at vision
    s = m.snapshot()
    assert s["frames"] == 2
    assert s["end_to_end"]["n"] == 1
    assert s["end_to_end"]["p50_ms"] == pytest.approx(3.0)
    assert s["processing"]["n"] == 2
    assert s["stages"]["vision"]["n"] == 2
    assert s["stages"]["dequeued"]["p50_ms"] == pytest.approx(0.75)  # the queue wait
    assert s["stages"]["vision"]["max_ms"] == pytest.approx(3.0)
    assert s["stages"]["scheduled"]["p50_ms"] == pytest.approx(1.0)


def test_monitor_counts_are_the_snapshot_s_counters_and_rate():
    """The Camera screen's cheap read: the same counters and rate as the snapshot."""
    m = LatencyMonitor(["vision"])
    for k in range(5):
        f = frame(k, arrival=k / 60, dequeued=k / 60 + 0.001, vision=k / 60 + 0.004)
        m.arrived(f)
        m.record(f)
    m.dropped(2)
    m.dropped(camera=True)
    s, c = m.snapshot(), m.counts()
    assert c == {k: s[k] for k in ("fps", "frames", "dropped_queue", "dropped_camera", "errors")}
    assert (c["frames"], c["dropped_queue"], c["dropped_camera"]) == (5, 2, 1)
    assert c["fps"] == pytest.approx(60.0, rel=0.01)


def test_loop_stamps_every_stage_in_order_and_stops_a_frame_on_false():
    seen: list[Frame] = []

    def vision(f, work):
        work["hand"] = f.seq % 2 == 0

    def effect(f, work):
        return None if work["hand"] else False

    def out(f, work):
        seen.append(f)

    loop = FrameLoop(ListCamera(10), [("vision", vision), ("effect", effect), ("scheduled", out)])
    for _ in range(10):
        f = loop.camera.read()
        f.stamp(ARRIVAL, 0.0)
        loop.process(f)
    assert [f.seq for f in seen] == [0, 2, 4, 6, 8]
    for f in seen:
        assert list(f.stamps_s) == [ARRIVAL, "dequeued", "vision", "effect", "scheduled"]
        ts = list(f.stamps_s.values())
        assert ts == sorted(ts)
    snap = loop.monitor.snapshot()
    assert snap["frames"] == 10 and snap["end_to_end"]["n"] == 5
    assert snap["cpu_per_frame"]["n"] == 10 and snap["cpu_per_frame"]["max_ms"] >= 0.0
    assert snap["cpu_stages"]["vision"]["n"] == 10 and snap["cpu_stages"]["scheduled"]["n"] == 5


def test_a_slow_stage_drops_the_oldest_frames_and_processes_the_newest():
    gate = threading.Event()
    done: list[int] = []

    def slow(f, work):
        gate.wait(5)
        done.append(f.seq)

    loop = FrameLoop(ListCamera(12), [("vision", slow)], queue_size=2).start()
    try:
        # the camera thread delivers all 12 frames while the first one is held
        for _ in range(500):
            if loop.frames_in == 12:
                break
            threading.Event().wait(0.01)
        gate.set()
        for _ in range(500):
            if loop.monitor.frames + loop.monitor.dropped_queue >= 12:
                break
            threading.Event().wait(0.01)
    finally:
        loop.stop()
    assert loop.frames_in == 12
    assert loop.monitor.dropped_queue >= 1
    assert loop.monitor.frames + loop.monitor.dropped_queue == 12
    assert done[-2:] == [10, 11]  # the newest frames were kept
    assert done == sorted(done)


def test_a_failing_stage_is_counted_and_the_loop_goes_on():
    def bad(f, work):
        if f.seq == 1:
            raise RuntimeError("boom")

    loop = FrameLoop(ListCamera(3), [("vision", bad)])
    for _ in range(3):
        f = loop.camera.read()
        f.stamp(ARRIVAL, 0.0)
        loop.process(f)
    assert loop.monitor.errors == 1
    assert loop.monitor.frames == 2
    assert "boom" in loop.last_error and "vision" in loop.last_error


def test_stage_names_must_be_unique():
    with pytest.raises(ValueError):
        FrameLoop(ListCamera(0), [("a", print), ("a", print)])
    with pytest.raises(ValueError):
        FrameLoop(ListCamera(0), [(ARRIVAL, print)])


def test_camera_drops_count_from_the_loop_start():
    """A camera kept open before the loop (its screen hidden) reports what it lost then:
    the loop counts only what the camera drops while the loop reads it."""
    import time

    class Kept(ListCamera):
        def __init__(self) -> None:
            super().__init__(60)
            self.dropped = 500  # before this loop
            self.go = threading.Event()  # the second 30 frames wait for it

        def read(self, timeout_s: float = 0.1):
            if self.k >= 30 and not self.go.wait(timeout_s):
                return None
            return super().read(timeout_s)

        def status(self) -> dict:
            return {"dropped": self.dropped}

    cam = Kept()
    loop = FrameLoop(cam, [("vision", lambda f, w: None)]).start()
    try:
        deadline = time.monotonic() + 5
        while loop.frames_in < 30 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert loop.monitor.snapshot()["dropped_camera"] == 0
        cam.dropped += 2  # now the camera loses two while the loop reads
        cam.go.set()
        while loop.monitor.snapshot()["dropped_camera"] == 0 and time.monotonic() < deadline:
            time.sleep(0.01)  # polled every 30 frames
        assert loop.monitor.snapshot()["dropped_camera"] == 2
    finally:
        loop.stop()
