"""Progress reports and cancellation for long gesture work (synthesis, features, training).

Long functions take ``progress: Progress | None`` (called with the fraction done, 0..1,
and a short message) and ``cancelled: CancelCheck | None`` (polled between steps; when
it returns True the function raises ``Cancelled`` and writes nothing more). The console
runs them in a thread worker; the CLI prints the messages.
"""

from __future__ import annotations

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
