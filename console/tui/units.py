"""Numbers on screen with their units and meaning (issue 27): a block size also in time,
a range of levels that may be negative written so it reads as one ("grey -15 to 17",
never "-15-17"), a camera control said in its driver's terms (the twin's multiplier, a
real driver's raw value or automatic), and no raw index where a word says it ("no item"
for the knob's -1)."""

from __future__ import annotations

import math
from typing import Any


def _num(v: Any) -> float | None:
    try:
        x = float(v)
    except (TypeError, ValueError):
        return None
    return x if math.isfinite(x) else None


def rate_words(rate_hz: Any) -> str:
    """A sample rate as read: ``48 kHz``, ``44.1 kHz``, ``800 Hz``; ``?`` unknown."""
    r = _num(rate_hz)
    if r is None:
        return "?"
    return f"{r / 1000:g} kHz" if r >= 1000 else f"{r:g} Hz"


def block_words(block: Any, rate_hz: Any) -> str:
    """An audio block in samples and in time: ``block 64 samples = 1.33 ms at 48 kHz``."""
    n, r = _num(block), _num(rate_hz)
    if n is None:
        return f"block ? samples at {rate_words(rate_hz)}"
    if r is None or r <= 0:
        return f"block {n:g} samples"
    return f"block {n:g} samples = {n / r * 1e3:.2f} ms at {rate_words(r)}"


def span_words(lo: float, hi: float, fmt: str = ".0f") -> str:
    """A range whose ends may be negative, unambiguous: ``-15 to 17`` (``-15-17`` reads as
    a subtraction or two negatives)."""
    return f"{lo:{fmt}} to {hi:{fmt}}"


def view_levels(view: str, lo: float, hi: float) -> str:
    """The range a Camera view shows, in its own terms: the camera's grey levels
    (``grey 8 to 81``); the diff, a difference over the background in grey levels
    (``diff -1..+31 grey levels over background``); the high-pass, the detail over its
    blur; the body view, a mask (white: over the body threshold)."""
    if view == "diff":
        return f"diff {lo:+.0f}..{hi:+.0f} grey levels over background"
    if view == "highpass":
        return f"high-pass {lo:+.0f}..{hi:+.0f} grey levels over its blur"
    if view == "body":
        return "body: white over the body threshold"
    return f"grey {span_words(lo, hi)}"


#: a camera control's value in the words of the twin's driver: a multiplier on the light
TWIN_CONTROL = "x{v:g}"
#: a real camera driver's control: its raw value (V4L2/UVC units differ per camera), or
#: automatic (-1 and below, as the OpenCV driver takes them)
RAW_CONTROL = "{v:g} (raw driver value)"


def control_words(key: str, value: float, driver: str) -> str:
    """A camera control (exposure, gain) as the side panel shows it: the twin's a
    multiplier (``x1``), a real driver's ``auto`` or its raw value."""
    if driver == "twin":
        return f"{key} " + TWIN_CONTROL.format(v=value)
    if value < 0:
        return f"{key} auto"
    return f"{key} " + RAW_CONTROL.format(v=value)


def item_words(item: Any) -> str:
    """The knob's item under the finger: ``item 3``, ``no item`` (its -1: between items
    or not touched)."""
    n = _num(item)
    if n is None or n < 0:
        return "no item"
    return f"item {n:g}"
