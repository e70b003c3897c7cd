"""The device buffer a paced audio driver keeps: ``[audio] buffer_ms`` for every driver.

A sound card plays its buffer while the audio thread is off the CPU; the thread may wake
up to the buffer less one block late before the card finds it empty. ``[audio]
buffer_ms`` sets the buffer for every driver (the twin's paced card, PortAudio's
suggested latency); 0 keeps the driver's own (``[twin_audio] buffer_periods``,
``[sounddevice] latency_s``). `haptable doctor --buffer` sizes it for the machine
(``console.runtime.buffer_doctor``).
"""

from __future__ import annotations

import math
from typing import Any


def block_ms(profile: Any) -> float:
    """One audio block of the profile, in ms."""
    return 1e3 * float(profile.get("audio.block_size")) / float(profile.get("audio.sample_rate_hz"))


def _want_ms(profile: Any) -> float:
    """``[audio] buffer_ms`` (0 when the profile has no such key: a driver's own test
    profile)."""
    try:
        return float(profile.get("audio.buffer_ms") or 0.0)
    except (KeyError, TypeError, ValueError):
        return 0.0


def buffer_periods(profile: Any, own_periods: int) -> int:
    """The blocks a paced driver keeps ahead: ``[audio] buffer_ms`` in whole blocks when
    set (at least 2), else the driver's own ``own_periods``."""
    want_ms = _want_ms(profile)
    if want_ms <= 0:
        return max(2, int(own_periods))
    return max(2, math.ceil(want_ms / block_ms(profile) - 1e-9))


def buffer_latency_s(profile: Any, own_latency_s: float) -> float:
    """PortAudio's suggested output latency: ``[audio] buffer_ms`` when set, else the
    driver's own (0: PortAudio's lowest)."""
    want_ms = _want_ms(profile)
    return want_ms / 1e3 if want_ms > 0 else float(own_latency_s)
