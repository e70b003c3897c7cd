"""What ``haptable frf latency`` reports: the measured loopback round trip next to what
PortAudio claims, and the output latency it implies.

The round trip (output handed to the driver -> the same sample back on the loopback
input, stamped by the clock of the output block filled in the same callback) is the
output latency plus the input's. A loopback alone cannot split them: the input's share
is PortAudio's claimed input latency when that is plausible (0 < claim < round trip),
else one block (at most half the round trip; said so in ``input_share_from``); the rest is the
``measured_output_latency_ms`` that ``--save`` stores and ``bench flow-latency`` adds.
"""

from __future__ import annotations

import math
from typing import Any


def _ms(v: Any) -> float | None:
    try:
        v = float(v)
    except (TypeError, ValueError):
        return None
    return round(v * 1e3, 3) if math.isfinite(v) else None


def latency_report(lag_samples: float, fs_hz: int, audio: dict[str, Any]) -> dict[str, Any]:
    """The report for a round trip of ``lag_samples`` at ``fs_hz``; ``audio``: the
    outputs' driver status (``latency_s``, ``input_latency_s``, ``block_size``)."""
    rt_ms = lag_samples / fs_hz * 1e3
    out_ms, in_ms = _ms(audio.get("latency_s")), _ms(audio.get("input_latency_s"))
    block = audio.get("block_size")
    if in_ms is not None and 0 < in_ms < rt_ms:
        share, why = in_ms, "PortAudio's claimed input latency"
    elif block:
        share = min(float(block) / fs_hz * 1e3, rt_ms / 2)
        why = "one block (no input latency claimed: a block reaches the callback whole)"
    else:
        share, why = rt_ms / 2, "half the round trip (no input latency claimed)"
    claimed_rt = None if out_ms is None or in_ms is None else round(out_ms + in_ms, 3)
    return {
        "round_trip_samples": round(float(lag_samples), 2),
        "round_trip_ms": round(rt_ms, 3),
        "portaudio_output_latency_ms": out_ms,
        "portaudio_input_latency_ms": in_ms,
        "portaudio_round_trip_ms": claimed_rt,
        "measured_output_latency_ms": round(rt_ms - share, 3),
        "input_share_ms": round(share, 3),
        "input_share_from": why,
        "block_size": block,
        "sample_rate_hz": fs_hz,
    }
