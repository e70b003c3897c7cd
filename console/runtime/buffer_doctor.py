"""The device buffer this machine needs: `haptable doctor --buffer SECONDS [--save]`
(``[audio] buffer_ms``, read by the drivers through ``console.core.device_buffer``).

A sound card plays its buffer while the audio thread is off the CPU; the thread may wake
up to the buffer less one block late before the card finds it empty (an underrun: on
every driver the last sample is held and ramped, never a step, but the sound stops).
How late it wakes is the machine's: a tuned lab PC with real-time priority stays within
a block or two; a virtual machine's host can hold every virtual CPU for 30 ms. The only
cure on a machine that stalls is a longer buffer, paid for in output latency, as audio
tools let their users choose (a JACK period count, a PortAudio latency).

``[audio] buffer_ms`` sets it for every driver (the twin's paced card and PortAudio's
suggested latency); 0 keeps the driver's own (``[twin_audio] buffer_periods``,
``[sounddevice] latency_s``). The doctor measures the machine with the real-time probe
(``console.runtime.jitter``, a FIFO thread waking every block, as the audio thread does)
and sizes the buffer to cover the latest wake seen with a margin.
"""

from __future__ import annotations

import math
from typing import Any

from console.core.device_buffer import block_ms, buffer_periods

#: The recommended buffer covers the latest wake seen times this (rarer, longer stalls
#: than the probe saw in its minute are likely: the margin is the guess, said as one).
MARGIN = 1.5
#: Never recommend less than the twin's default (3 blocks: 2 of slack).
MIN_PERIODS = 3
#: A buffer longer than this is refused as a recommendation: the machine cannot play
#: haptics in time (a flow under a hand would start this late), and on a real card an
#: e-stop's ramp waits behind what the card already holds (the twin rewrites its queue).
MAX_BUFFER_MS = 100.0


def recommend(late_max_ms: float, period_ms: float) -> dict[str, float | int]:
    """The buffer covering a wake ``late_max_ms`` late with the margin: whole blocks, one
    more than the slack needs, at least ``MIN_PERIODS``."""
    slack_ms = MARGIN * max(0.0, late_max_ms)
    periods = max(MIN_PERIODS, math.ceil(slack_ms / period_ms - 1e-9) + 1)
    return {"periods": periods, "buffer_ms": round(periods * period_ms, 3)}


def measure(profile: Any, seconds: float) -> dict[str, Any]:
    """Run the real-time probe for ``seconds`` at the profile's block period with the
    profile's current buffer; the recommendation beside it."""
    # lazy: the probe's module starts a process; `haptable doctor` without --buffer skips it
    from console.runtime.jitter import finish_probe, start_probe

    period_ms = block_ms(profile)
    now_periods = buffer_periods(profile, _own_periods(profile))
    slack_s = (now_periods - 1) * period_ms / 1e3
    got = finish_probe(start_probe(seconds, period_ms / 1e3, slack_s), timeout_s=seconds + 30)
    if "error" in got:
        return got
    rec = recommend(float(got["late_max_ms"]), period_ms)
    return {
        **got,
        "seconds": seconds,
        "block_ms": round(period_ms, 3),
        "buffer_now_ms": round(now_periods * period_ms, 3),
        "recommended_buffer_ms": rec["buffer_ms"],
        "recommended_periods": rec["periods"],
        "too_long": rec["buffer_ms"] > MAX_BUFFER_MS,
    }


def _own_periods(profile: Any) -> int:
    try:
        return int(profile.get("twin_audio.buffer_periods"))
    except Exception:  # no twin plugin: a real card's driver fills 2-4 periods ahead
        return MIN_PERIODS


def describe(got: dict[str, Any]) -> list[str]:
    """The doctor's lines for a measurement."""
    if "error" in got:
        return [f"  audio      buffer       error     the probe failed: {got['error']}"]
    late = (
        f"the audio thread woke up to {got['late_max_ms']:g} ms late in {got['seconds']:g} s "
        f"(p99 {got['late_p99_ms']:g} ms, p99.9 {got['late_p999_ms']:g} ms"
        + ("" if got["realtime_priority"] else ", without real-time priority")
        + ")"
    )
    now, rec = got["buffer_now_ms"], got["recommended_buffer_ms"]
    lines = [f"  audio      buffer       {'ok' if rec <= now else 'short':<9} {late}"]
    if got["too_long"]:
        lines.append(
            f"  {'':<10} {'':<12} fix: this machine stalls too long for haptics ({rec:g} ms "
            f"of buffer needed): give the audio thread real-time priority or use a quieter "
            f"machine"
        )
    elif rec > now:
        dry = f"the {now:.1f} ms buffer would have run dry {int(got['late_over_slack'])} times"
        cost = f"[audio] buffer_ms = {rec:.1f} (adds {rec - now:.1f} ms of output latency)"
        if got.get("saved_to"):
            lines.append(f"  {'':<10} {'':<12} {dry}: saved {cost} in {got['saved_to']}")
        else:
            lines.append(
                f"  {'':<10} {'':<12} fix: {dry}: set {cost}: "
                f"haptable doctor --buffer {got['seconds']:g} --save"
            )
    else:
        lines.append(
            f"  {'':<10} {'':<12} the {now:.1f} ms buffer covers it ({rec:.1f} ms would be enough)"
        )
    return lines
