"""Progress reports and cancellation for long gesture work (synthesis, features, training).

Long functions take ``progress: Progress | None`` (called with the fraction done, 0..1,
and a short message) and ``cancelled: CancelCheck | None`` (polled between steps; when
it returns True the function raises ``Cancelled`` and writes nothing more). The console
runs them in a thread worker; the CLI prints the messages.
"""

from __future__ import annotations

import time
from collections.abc import Callable

Progress = Callable[[float, str], None]
CancelCheck = Callable[[], bool]


class Cancelled(Exception):
    """Raised by a long function when its ``cancelled()`` check returned True."""


def step(progress: Progress | None, cancelled: CancelCheck | None, frac: float, msg: str) -> None:
    """Raise ``Cancelled`` if asked to stop, else report ``frac`` (clipped to 0..1)."""
    if cancelled is not None and cancelled():
        raise Cancelled(msg)
    if progress is not None:
        progress(min(1.0, max(0.0, float(frac))), msg)


def part(progress: Progress | None, lo: float, hi: float) -> Progress | None:
    """A ``Progress`` for a sub-task that fills ``lo``..``hi`` of the whole."""
    if progress is None:
        return None
    return lambda frac, msg: progress(lo + (hi - lo) * frac, msg)


class ProgressLine:
    """A command's progress line on a terminal, rewritten in place: the share done, which
    never goes back (a later step that reports less keeps the furthest), the step's
    message and the time left once the pace tells it (``seconds_left``: from the second
    second and 2 % on); ``write(text, done)`` puts it out."""

    def __init__(
        self, write: Callable[[str, bool], None], clock: Callable[[], float] = time.monotonic
    ) -> None:
        self.write = write
        self.clock = clock
        self.t0 = self.clock()
        self.frac = 0.0

    def __call__(self, frac: float, msg: str) -> None:
        # lazy: the console's time-left words, loaded when a line is first written
        from console.plugin_api.tui import left_words, seconds_left

        self.frac = max(self.frac, min(1.0, float(frac)))
        done = self.frac >= 1.0
        left = None if done else seconds_left(self.clock() - self.t0, self.frac)
        words = left_words(left)
        self.write(f"{self.frac:4.0%} {msg}" + (f" ({words})" if words else ""), done)
