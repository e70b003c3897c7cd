"""Watchdog: silences the outputs when the frame loop stalls longer than a limit.

The loop reports how long it has been stuck and where (``FrameLoop.stall``): a frame
held in one stage, or no frame arriving from the camera. Past ``limit_s`` the watchdog
calls ``on_stall(reason)`` once (the runtime passes the safety gate's e-stop, so every
output goes silent and every relay opens) and stays tripped until ``reset()``.

The limit is the profile's ``[runtime] watchdog_ms``.
"""

from __future__ import annotations

import logging
import os
import threading
import time
from collections.abc import Callable
from typing import Protocol

from console.core.realtime import SUPPORT_PRIORITY, realtime_priority

log = logging.getLogger("haptable.watchdog")


class Stallable(Protocol):
    def stall(self, now_s: float | None = None) -> tuple[float, str]: ...


def stall_reason(
    stuck_s: float, where: str, limit_s: float, load: tuple[float, int] | None = None
) -> str:
    """The e-stop reason the operator reads; ``load`` (1-minute load average, cores; the
    machine's now when None): past one runnable process per core the reason says the
    machine was overloaded, the likeliest cause of a stall then."""
    stuck = "forever" if stuck_s == float("inf") else f"{stuck_s * 1e3:.0f} ms"
    reason = (
        f"runtime watchdog: frame loop stalled {stuck} in {where} "
        f"(limit [runtime] watchdog_ms = {limit_s * 1e3:.0f}); outputs silenced"
    )
    avg, cores = load if load is not None else _load_now()
    if cores > 0 and avg > cores:
        reason += (
            f"; the machine is overloaded (load average {avg:.1f} on {cores} cores): "
            "close other programs before resetting"
        )
    return reason


def _load_now() -> tuple[float, int]:
    try:
        return os.getloadavg()[0], len(os.sched_getaffinity(0))
    except (OSError, AttributeError):
        return 0.0, 0


class Watchdog:
    """Checks ``target.stall()`` every ``period_s``; trips once past ``limit_s``."""

    def __init__(
        self,
        target: Stallable,
        on_stall: Callable[[str], None],
        limit_s: float,
        period_s: float | None = None,
        realtime: bool = False,
    ) -> None:
        if not limit_s > 0:
            raise ValueError(f"watchdog limit {limit_s} s: must be positive")
        self.target = target
        self.on_stall = on_stall
        self.limit_s = float(limit_s)
        self.period_s = float(period_s) if period_s else min(self.limit_s / 4, 0.05)
        self.reason = ""
        self.realtime = realtime  # FIFO scheduling (a demo's loop is real-time too)
        self._tripped = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    @property
    def tripped(self) -> bool:
        return self._tripped.is_set()

    def check(self, now_s: float | None = None) -> bool:
        """One check; True if it tripped now."""
        if self.tripped:
            return False
        stuck, where = self.target.stall(now_s)
        if stuck <= self.limit_s:
            return False
        self.reason = stall_reason(stuck, where, self.limit_s)
        self._tripped.set()
        log.error("%s", self.reason)
        try:
            self.on_stall(self.reason)
        except Exception:  # the e-stop must not take the watchdog down with it
            log.exception("watchdog action failed")
        return True

    def reset(self) -> None:
        self.reason = ""
        self._tripped.clear()

    def start(self) -> Watchdog:
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="haptable-watchdog", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(1.0)

    def _run(self) -> None:
        if self.realtime:
            realtime_priority(SUPPORT_PRIORITY)
        while not self._stop.wait(self.period_s):
            self.check(time.monotonic())
