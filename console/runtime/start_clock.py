"""How far a demo's start is, by the time the same demo took to start last time.

A demo's process says only which step it is in ("opening the camera" covers the camera, the
background, the effects' libraries and the planner: seconds). ``StartClock`` turns the
time since Enter into a fraction that only moves forward and a time left, from the last
start of the same demo on this machine (``cache_dir("demo-starts.json")``), or
``DEFAULT_START_S`` the first time. ``done()`` keeps this start's time for the next.
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import Callable
from pathlib import Path

from console.core.time_left import left_words
from console.files.paths import cache_dir

#: the expected start when this machine has not started the demo yet (twin, 2 cores)
DEFAULT_START_S = 12.0
#: the fraction the clock reaches at the expected time; the rest waits for "running"
AT_EXPECTED = 0.9


def starts_path() -> Path:
    """Where the last start time of each demo is kept (it can be computed again)."""
    return cache_dir("demo-starts.json")


def _read(path: Path) -> dict:
    with contextlib.suppress(OSError, ValueError):
        got = json.loads(path.read_text())
        if isinstance(got, dict):
            return got
    return {}


class StartClock:
    """The start of demo ``name``: ``fraction_text(step)`` says how far, ``done()`` keeps
    its time. ``now``: the clock (tests give their own)."""

    def __init__(
        self,
        name: str,
        *,
        path: Path | None = None,
        now: Callable[[], float] = time.monotonic,
    ) -> None:
        self.name = name
        self.path = path or starts_path()
        self.now = now
        self.t0 = now()
        last = _read(self.path).get(name)
        ok = isinstance(last, int | float) and 0.1 < float(last) < 3600
        self.expected_s = float(last) if ok else DEFAULT_START_S
        self.learned = ok
        self._fraction = 0.0

    def elapsed_s(self) -> float:
        return max(0.0, self.now() - self.t0)

    def fraction(self, floor: float = 0.0) -> float:
        """Forward only: ``AT_EXPECTED`` at the expected time, then slowly towards 0.99;
        ``floor``: a fraction the demo reported itself (its preparation's)."""
        t, exp_s = self.elapsed_s(), self.expected_s
        f = AT_EXPECTED * t / exp_s if t < exp_s else 0.99 - (0.99 - AT_EXPECTED) * exp_s / t
        self._fraction = max(self._fraction, f, min(floor, 0.99))
        return self._fraction

    def left_text(self) -> str:
        """The time left as the operator reads it."""
        left = self.expected_s - self.elapsed_s()
        if left > 0:  # short: the line shares 80 columns with the bar
            return left_words(left) + ("" if self.learned else " (a guess)")
        than = "the last start" if self.learned else "guessed"
        return f"longer than {than} ({self.expected_s:.0f} s)"

    def fraction_text(self, step: str, floor: float = 0.0) -> tuple[float, str]:
        """The fraction and the line to show for the step the demo is in."""
        return self.fraction(floor), f"{step}, {self.elapsed_s():.0f} s, {self.left_text()}"

    def done(self) -> None:
        """The demo runs: keep this start's time for the next start's estimate."""
        data = _read(self.path)
        data[self.name] = round(self.elapsed_s(), 2)
        with contextlib.suppress(OSError):
            self.path.parent.mkdir(parents=True, exist_ok=True)
            tmp = self.path.with_suffix(".tmp")
            tmp.write_text(json.dumps(data))
            tmp.replace(self.path)
