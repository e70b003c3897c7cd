"""What the gate pulls samples from, and the guard that runs plugin code off the audio
thread: ``SourceCaller`` waits at most ``[limits] source_stall_ms`` for a block, and an e-stop
ends the wait at once."""

from __future__ import annotations

import queue
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np


class Source:
    """What the gate pulls samples from (the output scheduler)."""

    def next_block(self, n: int) -> tuple[np.ndarray, np.ndarray] | None:  # pragma: no cover
        raise NotImplementedError

    @property
    def idle(self) -> bool:  # pragma: no cover
        return True

    def abort(self, reason: str) -> None:  # pragma: no cover
        """Drop everything queued (called by the e-stop)."""


class SourceStalled(Exception):
    """A source did not answer within its time (or is still inside an earlier call)."""


class SourceInterrupted(Exception):
    """An e-stop ended the wait for a source."""


class SourceCaller:
    """Runs plugin code (``fn(n)``) on a thread of its own so that it never holds the audio
    thread: the caller waits at most ``timeout_s``, or until ``interrupt()`` (the e-stop).
    A call that is still running makes every later call fail at once (the source stalled);
    its late result is dropped. The hand-over is two C-level queues (no Python locks)."""

    def __init__(self, name: str) -> None:
        self.name = name
        self._req: queue.SimpleQueue = queue.SimpleQueue()
        self._res: queue.SimpleQueue = queue.SimpleQueue()
        self._busy = False
        self._gen = 0
        self._interrupts = 0
        self._thread: threading.Thread | None = None

    @property
    def interrupts(self) -> int:
        """How many interrupts so far (``call(..., since=)`` counts the ones after)."""
        return self._interrupts

    def call(
        self, fn: Callable[[int], Any], n: int, timeout_s: float, *, since: int | None = None
    ) -> Any:
        """``fn(n)`` on the guarded thread. An interrupt after ``since`` (``interrupts`` as
        the caller read it, e.g. with its e-stop flag; default: now) ends the wait."""
        if self._busy:
            raise SourceStalled(f"{self.name} is still inside an earlier call")
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name=self.name, daemon=True)
            self._thread.start()
        self._gen += 1
        gen, seen = self._gen, self._interrupts if since is None else since
        if self._interrupts > seen:  # an e-stop came between the caller's look and now
            raise SourceInterrupted(f"{self.name}: interrupted by the e-stop")
        self._busy = True
        self._req.put((gen, fn, n))
        deadline = time.monotonic() + timeout_s
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise SourceStalled(
                    f"{self.name} gave no block within {timeout_s * 1e3:.0f} ms "
                    f"([limits] source_stall_ms)"
                )
            try:
                item = self._res.get(timeout=left)
            except queue.Empty:
                continue
            if item[0] == "interrupt":
                if item[1] > seen:
                    raise SourceInterrupted(f"{self.name}: interrupted by the e-stop")
                continue
            if item[0] != gen:
                continue  # the late answer to an abandoned call
            if not item[1]:
                raise item[2]
            return item[2]

    def interrupt(self) -> None:
        self._interrupts += 1
        self._res.put(("interrupt", self._interrupts))

    def _run(self) -> None:
        from console.realtime import AUDIO_PRIORITY, realtime_priority

        realtime_priority(AUDIO_PRIORITY)  # it stands in for the audio thread
        while True:
            gen, fn, n = self._req.get()
            try:
                res: tuple[bool, Any] = (True, fn(n))
            except BaseException as exc:  # handed to the caller, never lost
                res = (False, exc)
            self._busy = False
            self._res.put((gen, *res))
