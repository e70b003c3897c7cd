"""Latency monitor: per-stage ring buffers of durations, frame rate and drop counters.

The frame loop stamps each frame as it passes a stage (``Frame.stamp(stage, t_s)`` on the
``time.monotonic()`` clock). ``LatencyMonitor.record(frame)`` turns the stamps into
per-stage durations (each stamp minus the one before it) and an end-to-end time: arrival to
the output stage's stamp (``scheduled``), only for frames that scheduled output; a loop
without that stage schedules none and has no end-to-end time (its ``processing`` is what
a frame cost). ``snapshot()`` is what the console shows: p50/p99/max per stage in
milliseconds, fps, frames seen and dropped.

Stage names are whatever the loop stamps; the loop uses ``arrival`` (the frame was taken
from the camera), ``dequeued`` (processing began: its duration is the queue wait), then
``vision``, ``classify``, ``scene``, ``effect``, ``scheduled``
(the first output sample of the frame's effect was handed to the output scheduler).
"""

from __future__ import annotations

import threading
from collections.abc import Iterable

import numpy as np

from console.core.bench_stats import summarize_s
from console.core.types import Frame

#: The stage a frame's processing is measured from (the camera thread stamps it).
ARRIVAL = "arrival"
#: The processing thread took the frame from the queue (its duration: the queue wait).
DEQUEUED = "dequeued"
#: The stage a frame reaches only when its decision scheduled an output sample.
OUTPUT_STAGE = "scheduled"
#: Arrival to the end stage's stamp (default ``OUTPUT_STAGE``), for frames that reached
#: it: from frame arrival to the first output sample scheduled.
END_TO_END = "end_to_end"
#: Arrival to the last stamp of every frame (the processing time a frame cost).
PROCESSING = "processing"
#: CPU time the processing thread spent on a frame (``time.thread_time``): the work
#: itself, without waiting for a CPU on a busy machine.
CPU = "cpu"


class Ring:
    """A fixed-size ring of float samples (seconds): O(1) append, no allocation."""

    def __init__(self, size: int) -> None:
        if size < 1:
            raise ValueError(f"ring size {size}: must be at least 1")
        self._buf = np.zeros(int(size))
        self._n = 0  # samples ever added

    def add(self, x_s: float) -> None:
        self._buf[self._n % self._buf.size] = x_s
        self._n += 1

    def values(self) -> np.ndarray:
        """The samples held (oldest first is not guaranteed; order does not matter)."""
        return self._buf[: min(self._n, self._buf.size)].copy()

    @property
    def count(self) -> int:
        return self._n


def stage_durations_s(stamps_s: dict[str, float], order: Iterable[str]) -> dict[str, float]:
    """Duration of each stamped stage: its stamp minus the previous stamped stage's.

    Stages in ``order`` that the frame did not pass are skipped (a frame without a hand
    has no ``effect`` stamp), so durations always add up to the end-to-end time.
    """
    out: dict[str, float] = {}
    prev: float | None = None
    for name in order:
        t = stamps_s.get(name)
        if t is None:
            continue
        if prev is not None:
            out[name] = t - prev
        prev = t
    return out


#: n, p50, p99 and max in milliseconds (NaN when empty): the benchmarks' summary.
percentiles_ms = summarize_s


class LatencyMonitor:
    """Per-stage p50/p99 over the last ``size`` frames, fps and drops. Thread-safe.
    ``end_stage``: where the end-to-end time ends (default ``OUTPUT_STAGE`` when the loop
    has it, else none is kept)."""

    def __init__(self, stages: Iterable[str], size: int = 1200, end_stage: str | None = None):
        self.order = (ARRIVAL, DEQUEUED, *[s for s in stages if s not in (ARRIVAL, DEQUEUED)])
        # no output stage: no frame schedules output, so none has an end-to-end time
        default = OUTPUT_STAGE if OUTPUT_STAGE in self.order else None
        self.end_stage: str | None = end_stage or default
        if self.end_stage is not None and self.end_stage not in self.order:
            raise ValueError(f"end stage {self.end_stage!r} is not one of {self.order}")
        self.size = int(size)
        self._lock = threading.Lock()
        self._rings: dict[str, Ring] = {
            s: Ring(size) for s in (*self.order[1:], END_TO_END, PROCESSING, CPU)
        }
        self._cpu_rings: dict[str, Ring] = {}  # CPU time per stage
        self._capture = Ring(size)  # camera capture -> arrival (driver latency)
        self._arrivals = Ring(121)  # arrival times for the frame rate
        self._last_arrival: float | None = None
        self.frames = 0
        self.dropped_queue = 0  # frames the loop discarded (processing too slow)
        self.dropped_camera = 0  # frames the camera reports lost
        self.errors = 0  # frames whose processing raised

    def arrived(self, frame: Frame) -> None:
        """A frame was taken from the camera (called by the camera thread)."""
        t = frame.stamps_s.get(ARRIVAL)
        if t is None:
            return
        with self._lock:
            self._arrivals.add(t)
            self._last_arrival = t
            if frame.t_capture_s and t >= frame.t_capture_s:
                self._capture.add(t - frame.t_capture_s)

    def record(
        self,
        frame: Frame,
        cpu_s: float | None = None,
        stage_cpu_s: dict[str, float] | None = None,
    ) -> dict[str, float]:
        """Add one processed frame's stage durations (and the CPU time it and each stage
        cost, when known); returns the durations (seconds)."""
        d = stage_durations_s(frame.stamps_s, self.order)
        stamped = [frame.stamps_s[s] for s in self.order if s in frame.stamps_s]
        with self._lock:
            self.frames += 1
            if cpu_s is not None:
                self._rings[CPU].add(cpu_s)
            for name, x in (stage_cpu_s or {}).items():
                ring = self._cpu_rings.get(name)
                if ring is None:
                    ring = self._cpu_rings[name] = Ring(self.size)
                ring.add(x)
            for name, x in d.items():
                self._rings[name].add(x)
            if len(stamped) >= 2 and ARRIVAL in frame.stamps_s:
                self._rings[PROCESSING].add(stamped[-1] - stamped[0])
                if self.end_stage is not None and self.end_stage in frame.stamps_s:
                    self._rings[END_TO_END].add(
                        frame.stamps_s[self.end_stage] - frame.stamps_s[ARRIVAL]
                    )
        return d

    def dropped(self, n: int = 1, *, camera: bool = False) -> None:
        with self._lock:
            if camera:
                self.dropped_camera += n
            else:
                self.dropped_queue += n

    def failed(self) -> None:
        with self._lock:
            self.errors += 1

    def values_s(self, name: str) -> np.ndarray:
        """The durations (s) held for a stage, ``end_to_end`` or ``processing``."""
        with self._lock:
            return self._rings[name].values()

    def fps(self) -> float:
        """Frames arriving per second over the last (up to) 120 frames."""
        with self._lock:
            t = np.sort(self._arrivals.values())
        if t.size < 2 or t[-1] <= t[0]:
            return 0.0
        return float((t.size - 1) / (t[-1] - t[0]))

    def counts(self) -> dict:
        """The frame counters and the rate alone (``snapshot``'s without the
        percentiles, which cost: the Camera screen reads these twice a second)."""
        with self._lock:
            counts = {
                "frames": self.frames,
                "dropped_queue": self.dropped_queue,
                "dropped_camera": self.dropped_camera,
                "errors": self.errors,
            }
        return {"fps": round(self.fps(), 2), **counts}

    def snapshot(self) -> dict:
        """Everything the console shows, as plain JSON values."""
        with self._lock:
            rings = {k: r.values() for k, r in self._rings.items()}
            cpu_rings = {k: r.values() for k, r in self._cpu_rings.items()}
            capture = self._capture.values()
            counts = {
                "frames": self.frames,
                "dropped_queue": self.dropped_queue,
                "dropped_camera": self.dropped_camera,
                "errors": self.errors,
            }
        stages = {name: percentiles_ms(rings[name]) for name in self.order[1:]}
        return {
            "fps": round(self.fps(), 2),
            **counts,
            "stages": stages,
            "end_stage": self.end_stage,
            "end_to_end": percentiles_ms(rings[END_TO_END]),
            "processing": percentiles_ms(rings[PROCESSING]),
            "cpu_per_frame": percentiles_ms(rings[CPU]),
            "cpu_stages": {k: percentiles_ms(v) for k, v in cpu_rings.items()},
            "capture_to_arrival": percentiles_ms(capture),
            "window_frames": self.size,
        }
