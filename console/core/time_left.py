"""The console's one rule for the time a long piece of work still needs, from how fast it
went so far, in words ("about 1 min 10 s left"): every progress line says it so (a count
alone, "33/50", said nothing of when it ends): ``LongWork``, the Studies run, the
Vibration measurement (``JobLeft``), Latency's measurement, a demo's start. One estimate
per job, steady (``Steady``: counts down between reports, never jumps up), the same
words everywhere (``left_words``). Pure: the TUI, the runtime and plugins share it."""

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


#: how far a time left may rise at a new report over its countdown: seconds, or share
RISE_S, RISE_SHARE = 1.0, 0.1


class Steady:
    """A time left as the operator reads it, steady: between reports of progress it
    counts down (the rate over the run so far said it; the clock alone is no news), and
    at a report it may rise over that countdown only by noise (``RISE_S`` or
    ``RISE_SHARE`` of it), so a slower stretch raises it gradually, never in jumps at
    every tick ("7 s, 9 s, 10 s left" at 28 to 38 %); once the countdown ran out (the
    work is later than said) the estimate stands."""

    def __init__(self, clock=time.monotonic) -> None:
        self.clock = clock
        self.value: float | None = None
        self.at = 0.0

    def reset(self) -> None:
        self.value = None

    def left(self, estimate: float | None, report: bool) -> float | None:
        """The time left to show now for ``estimate`` (None: unknown); ``report``: the
        work reported progress now (else a tick of the clock)."""
        now = self.clock()
        if self.value is None or estimate is None:
            self.value, self.at = estimate, now
            return estimate
        down = self.value - (now - self.at)
        if down <= 0.0:  # later than it said: the estimate (the pace so far) is the truth
            self.value, self.at = estimate, now
            return estimate
        rise = max(RISE_S, RISE_SHARE * down) if report else 0.0
        self.value, self.at = min(estimate, down + rise), now
        return self.value


class JobLeft:
    """One job's time left by the rule: from the pace since its first report (the share
    done counted from there: a first report past 0 does not skew it), from
    ``expected_s`` (the job's expected seconds, when known) until that pace tells, held
    ``Steady``. ``left(fraction)`` at a report; ``left()`` at a tick of the clock."""

    def __init__(self, expected_s: float | None = None, clock=None) -> None:
        self.expected_s = expected_s
        self.clock = clock or (lambda: time.monotonic())  # looked up at each call
        self._first: tuple[float, float] | None = None  # when, at which fraction
        self._fraction = 0.0
        self._steady = Steady(self.clock)

    def left(self, fraction: float | None = None) -> float | None:
        """The seconds to show now; ``fraction`` (0..1): a report, None: a tick."""
        now, report = self.clock(), fraction is not None
        frac = self._fraction if fraction is None else float(fraction)
        self._fraction = frac
        if self._first is None:
            self._first = (now, frac)
        t0, f0 = self._first
        if frac >= 1.0:
            return None
        done = (frac - f0) / (1.0 - f0) if f0 < 1.0 else 0.0
        estimate = seconds_left(now - t0, done)
        if estimate is None and self.expected_s is not None and now - t0 < self.expected_s:
            estimate = self.expected_s - (now - t0)
        return self._steady.left(estimate, report)

    def words(self, fraction: float | None = None) -> str:
        """``left`` as ``left_words`` says it ("" when unknown)."""
        return left_words(self.left(fraction))
