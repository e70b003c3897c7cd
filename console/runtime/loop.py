"""The frame loop: a camera thread feeding a processing thread through a bounded queue.

::

    camera thread: camera.read() -> stamp "arrival" -> FrameQueue (drops the OLDEST frame)
    processing thread: frame -> stage 1 -> stage 2 -> ... -> sinks

A stage is ``(name, fn)``; ``fn(frame, work)`` does its work (``work`` is a dict the
stages of one frame share: the vision result, the gesture, the scene's request ...) and
the loop stamps ``name`` on the frame when it returns. A stage that returns ``False``
ends the frame there (nothing to do further down: no hand, no request); its own stamp
is not set. A stage that returns ``PASSED`` did nothing this frame (an output stage that
scheduled no sample): its stamp is not set and the frame goes on. Sinks (``fn(frame, work)``, e.g. TUIO) run after the stages, untimed.

Nothing here touches the audio path: stages hand output to the scheduler with
non-blocking calls (``Outputs.play(plan, wait=False)``, a live stream's ``post``). The
queue never blocks the camera either: when processing falls behind, the oldest waiting
frame is discarded and counted (``LatencyMonitor.dropped_queue``).

``FrameLoop.stall(now)`` tells the watchdog how long the loop has been stuck and where.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from typing import Any

from console.core.contracts import Camera
from console.core.realtime import FRAMES_PRIORITY, realtime_priority
from console.core.types import Frame
from console.runtime.latency import ARRIVAL, DEQUEUED, LatencyMonitor

log = logging.getLogger("haptable.loop")

StageFn = Callable[[Frame, dict], Any]
Stage = tuple[str, StageFn]
Sink = Callable[[Frame, dict], None]


class _Passed:
    """The type of ``PASSED``."""

    def __repr__(self) -> str:
        return "PASSED"


#: a stage's answer when it did nothing this frame: not stamped, the frame goes on
PASSED = _Passed()


class FrameQueue:
    """A bounded FIFO whose ``put`` never blocks: when full it drops the oldest item."""

    def __init__(self, maxsize: int = 2) -> None:
        if maxsize < 1:
            raise ValueError(f"queue size {maxsize}: must be at least 1")
        self.maxsize = int(maxsize)
        self._items: deque = deque()
        self._cond = threading.Condition()
        self._closed = False

    def put(self, item: Any) -> Any | None:
        """Add ``item``; returns the item dropped to make room (or ``None``)."""
        with self._cond:
            dropped = self._items.popleft() if len(self._items) >= self.maxsize else None
            self._items.append(item)
            self._cond.notify()
            return dropped

    def get(self, timeout_s: float | None = None) -> Any | None:
        """The oldest item, or ``None`` after ``timeout_s`` or once closed and empty."""
        with self._cond:
            if not self._items and not self._closed:
                self._cond.wait(timeout_s)
            return self._items.popleft() if self._items else None

    def close(self) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()

    def __len__(self) -> int:
        with self._cond:
            return len(self._items)


class FrameLoop:
    """Camera thread + processing thread with per-stage stamps and a latency monitor."""

    def __init__(
        self,
        camera: Camera,
        stages: Sequence[Stage],
        *,
        monitor: LatencyMonitor | None = None,
        queue_size: int = 2,
        sinks: Iterable[Sink] = (),
        name: str = "loop",
        realtime: bool = False,
    ) -> None:
        names = [n for n, _ in stages]
        if len(set(names)) != len(names) or {ARRIVAL, DEQUEUED} & set(names):
            raise ValueError(
                f"stage names must be unique and not {ARRIVAL!r} or {DEQUEUED!r}: {names}"
            )
        self.camera = camera
        self.stages = list(stages)
        self.sinks = list(sinks)
        self.monitor = monitor or LatencyMonitor(names)
        self.queue = FrameQueue(queue_size)
        self.name = name
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._lock = threading.Lock()
        self._busy_since: float | None = None  # processing of the current frame began
        self._stage: str = ""
        self._last_arrival: float | None = None
        self._last_done: float | None = None
        self._camera_dropped_seen = 0
        self.last_error: str = ""
        self.frames_in = 0
        self.realtime = realtime  # ask for FIFO scheduling of both threads
        self.realtime_granted: bool | None = None  # what the system gave (None: not asked)

    # ------------------------------------------------------------------ control
    def start(self) -> FrameLoop:
        if self._threads:
            raise RuntimeError(f"{self.name}: already started")
        self._stop.clear()
        # the camera's drops from now on: frames it lost before this loop read are not
        # this pipeline's (a camera kept open while its screen was hidden)
        self._camera_dropped_seen = self._camera_dropped()
        self._threads = [
            threading.Thread(
                target=self._camera_run, name=f"haptable-{self.name}-camera", daemon=True
            ),
            threading.Thread(
                target=self._process_run, name=f"haptable-{self.name}-frames", daemon=True
            ),
        ]
        for t in self._threads:
            t.start()
        return self

    def stop(self, timeout_s: float = 2.0) -> None:
        """Stop both threads (the camera stays open: its owner closes it)."""
        self._stop.set()
        self.queue.close()
        for t in self._threads:
            t.join(timeout_s)

    @property
    def running(self) -> bool:
        return bool(self._threads) and not self._stop.is_set()

    def alive(self) -> bool:
        return bool(self._threads) and all(t.is_alive() for t in self._threads)

    def stall(self, now_s: float | None = None) -> tuple[float, str]:
        """(seconds stuck, where): a frame in a stage for long, or no frame arriving."""
        now = time.monotonic() if now_s is None else now_s
        with self._lock:
            busy, stage, last = self._busy_since, self._stage, self._last_arrival
        if self.running and not self.alive():
            return float("inf"), "a loop thread died" + (
                f" ({self.last_error})" if self.last_error else ""
            )
        if busy is not None:
            return now - busy, f"stage {stage!r}"
        if last is not None:
            return now - last, "camera (no frame arriving)"
        return 0.0, "not started"

    # ------------------------------------------------------------------ threads
    def _want_realtime(self) -> None:
        if self.realtime:
            self.realtime_granted = realtime_priority(FRAMES_PRIORITY)

    def _camera_run(self) -> None:
        self._want_realtime()
        cam = self.camera
        while not self._stop.is_set():
            try:
                frame = cam.read(0.05)
            except Exception as exc:  # a camera fault: the watchdog sees no frames
                self.last_error = f"camera read failed: {exc!r}"
                log.exception("camera read failed")
                time.sleep(0.05)
                continue
            if frame is None:
                continue
            frame.stamp(ARRIVAL, time.monotonic())
            with self._lock:
                self._last_arrival = frame.stamps_s[ARRIVAL]
                self.frames_in += 1
            self.monitor.arrived(frame)
            if self.queue.put(frame) is not None:
                self.monitor.dropped(1)
            self._poll_camera_drops()

    def _camera_dropped(self) -> int:
        try:
            return int(self.camera.status().get("dropped", 0) or 0)
        except Exception:
            return 0

    def _poll_camera_drops(self) -> None:
        if self.frames_in % 30:
            return
        n = self._camera_dropped()
        if n > self._camera_dropped_seen:
            self.monitor.dropped(n - self._camera_dropped_seen, camera=True)
            self._camera_dropped_seen = n

    def _process_run(self) -> None:
        self._want_realtime()
        while not self._stop.is_set():
            frame = self.queue.get(0.05)
            if frame is None:
                continue
            self.process(frame)

    def process(self, frame: Frame) -> dict:
        """Run one frame through the stages and sinks (the processing thread's body;
        benchmarks call it directly). Returns the frame's ``work`` dict."""
        work: dict = {}
        with self._lock:
            self._busy_since = time.monotonic()
        frame.stamp(DEQUEUED, self._busy_since)
        cpu0 = time.thread_time()
        cpu: dict[str, float] = {}
        try:
            for name, fn in self.stages:
                with self._lock:
                    self._stage = name
                c0 = time.thread_time()
                more = fn(frame, work)
                cpu[name] = time.thread_time() - c0
                if more is False:
                    break
                if more is not PASSED and name not in frame.stamps_s:
                    frame.stamp(name, time.monotonic())
            self.monitor.record(frame, time.thread_time() - cpu0, cpu)
            for sink in self.sinks:
                with self._lock:
                    self._stage = "sink"
                sink(frame, work)
        except Exception as exc:
            self.monitor.failed()
            self.last_error = f"{self._stage}: {type(exc).__name__}: {exc}"
            log.exception("frame %s failed in %s", frame.seq, self._stage)
        finally:
            with self._lock:
                self._busy_since = None
                self._stage = ""
                self._last_done = time.monotonic()
        return work
