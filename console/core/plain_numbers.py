"""Numbers in messages as a person writes them: ``99999 s``, ``0.00001 s``, ``100.001 s``;
never ``1e+05 s`` (Python's ``:g`` turns six digits and more, or a small fraction, into
an exponent: a duration typed as ``99999 s`` was echoed ``1e+05 s``)."""

from __future__ import annotations

import math

__all__ = ["plain_number", "plain_s"]

#: beyond these magnitudes a number is absurd for a message: ``:g`` says it
_LARGEST, _SMALLEST = 1e15, 1e-9


def plain_number(value: float, digits: int = 6) -> str:
    """``value`` in plain decimals, at most ``digits`` significant ones after the whole
    number's (``1/3`` is ``0.333333``, ``123456789`` stays whole), no trailing zeros."""
    v = float(value)
    if v == 0:
        return "0"
    if not math.isfinite(v) or not _SMALLEST <= abs(v) < _LARGEST:
        return f"{v:g}"
    decimals = max(0, digits - 1 - math.floor(math.log10(abs(v))))
    text = f"{v:.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def plain_s(seconds: float, digits: int = 6) -> str:
    """``seconds`` as a duration in a message: ``99999 s``."""
    return f"{plain_number(seconds, digits)} s"
