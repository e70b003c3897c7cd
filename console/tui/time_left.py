"""The time a long piece of work still needs, from how fast it went so far, in words
("about 1 min 10 s left"): the Studies screen's run and every ``LongWork`` job say it
beside their progress (a count alone, "33/50", said nothing of when it ends)."""

from __future__ import annotations

import math
import time

#: no estimate before this much of the work is done, nor before this many seconds
MIN_FRACTION = 0.02
MIN_ELAPSED_S = 1.0


def seconds_left(elapsed_s: float, fraction: float) -> float | None:
    """At a constant rate: ``elapsed_s`` for ``fraction`` of the work, so the rest takes
    ``elapsed_s * (1 - fraction) / fraction``; None while too little is done to tell."""
    if math.isnan(fraction) or fraction < MIN_FRACTION or elapsed_s < MIN_ELAPSED_S:
        return None
    return max(0.0, elapsed_s * (1.0 - min(fraction, 1.0)) / fraction)


def left_words(seconds: float | None) -> str:
    """``seconds`` as the operator reads it: "about 40 s left", "about 3 min 20 s left"
    (rounded up to 5 s past a minute, to 10 s past ten minutes), "" when unknown."""
    if seconds is None or not math.isfinite(seconds):
        return ""
    if seconds < 1.0:
        return "less than 1 s left"
    if seconds < 60:
        return f"about {math.ceil(seconds)} s left"
    step = 5 if seconds < 600 else 10
    s = int(math.ceil(seconds / step) * step)
    m, s = divmod(s, 60)
    if m >= 60:
        return f"about {m // 60} h {m % 60} min left"
    return f"about {m} min {s} s left" if s else f"about {m} min left"


class Pace:
    """Counts of done work over time, for the time left: ``start(done)`` when the work
    (re)starts (a resume, after a pause: the wait is not work), ``left(done, total)`` the
    seconds the rest takes at the pace since then (None until one more is done)."""

    def __init__(self, clock=time.monotonic) -> None:
        self.clock = clock
        self.t0: float | None = None
        self.done0 = 0

    def start(self, done: int) -> None:
        self.t0, self.done0 = self.clock(), done

    def stop(self) -> None:
        self.t0 = None

    def left(self, done: int, total: int) -> float | None:
        if self.t0 is None:
            self.start(done)
            return None
        n = done - self.done0
        if n <= 0 or total <= 0:
            return None
        return (self.clock() - self.t0) / n * max(total - done, 0)
