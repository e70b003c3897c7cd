"""``haptable bench audio-output``: how the profile's audio output keeps time, in silence.

The outputs are opened through the safety gate as usual and left idle (the gate feeds
zeros, relays stay open), so it is safe on the lab table. Reports the callback period
and the time spent in the gate's ``fill`` (p50/p99/max), underruns and output latency.
"""

from __future__ import annotations

import time
from typing import Any

from console.plugin_api import machine_info


def run(ctx: Any, quick: bool, duration_s: float | None = None) -> dict[str, Any]:
    seconds = duration_s if duration_s is not None else (2.0 if quick else 10.0)
    profile = ctx.profile
    fs = int(profile.get("audio.sample_rate_hz"))
    block = int(profile.get("audio.block_size"))
    with ctx.outputs(fast=False) as out:
        before = out.status()["audio"]
        t0_s = time.monotonic()
        time.sleep(seconds)
        wall_s = time.monotonic() - t0_s
        audio = out.status()["audio"]
    blocks = int(audio.get("blocks", 0)) - int(before.get("blocks", 0))
    played_s = blocks * block / fs
    return {
        "driver": profile.get("audio.driver"),
        "device": audio.get("device", ""),
        "sample_rate_hz": fs,
        "block_size": block,
        "nominal_period_ms": 1e3 * block / fs,
        "wall_s": wall_s,
        "blocks": blocks,
        "pace": played_s / wall_s if wall_s > 0 else float("nan"),  # 1.0 = real time
        "underruns": int(audio.get("underruns", 0)) - int(before.get("underruns", 0)),
        "latency_s": audio.get("latency_s"),
        "period_ms": audio.get("period_ms"),
        "fill_ms": audio.get("fill_ms"),
        "dac_lead_ms": audio.get("dac_lead_ms"),
        "machine": machine_info(),
    }
