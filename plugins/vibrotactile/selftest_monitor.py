"""The self-test with the amplifiers' monitor outputs as the sensor (no accelerometer).

Each ``amp_monitor`` input (``[audio_inputs.NAME] kind = 'amp_monitor'``, ``source`` the
output channel whose amplifier it watches, ``sensitivity`` the divider ratio) reads the
amplifier's output in volts at the actuators (``console.core.audio_inputs``). Per monitored
channel one short chirp plays through the safety gate on a path that channel drives (a
bus: the first patch on a relay; a channel-per-patch card: that patch), and

    gain = median over the band of |H1(monitor volts / volts the gate sent)|

says what the amplifier did with what the gate sent: ~1 on a healthy channel (its gain is
the one the profile names, which the gate's volts already include), ~0 on a dead one, off
by more than ``GAIN_DB`` on a weak channel or one set to another gain. The monitor sits
before the relays and the patches: a stuck relay, a detached or cracked patch and swapped
wires need the accelerometer (``selftest``).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from console.plugin_api import PATCHES, ChannelLayout, OutputPlan, Segment, UserError
from plugins.vibrotactile.roving import RovingSettings, h1
from plugins.vibrotactile.selftest import Finding, Layout
from plugins.vibrotactile.selftest_chirp import record_v

#: below this gain the channel gives nothing (-40 dB; the monitor's noise alone ~1e-4)
SILENT = 0.01
#: |20 log10 gain| above this: the channel's gain is not the profile's
GAIN_DB = 1.5
#: the chirp (volts at the actuators, seconds, hertz); one repeat: the monitor's SNR is high
CHIRP = RovingSettings(
    level_v=10.0, f_start_hz=20.0, f_stop_hz=700.0, sweep_s=0.25, tail_s=0.05, repeats=1,
    band_hz=(40.0, 625.0),
)  # fmt: skip


def monitored(profile: Any, specs: tuple) -> list[tuple[Any, str, str]]:
    """(input spec, output channel, patch to play) of every ``amp_monitor`` input."""
    names = list(ChannelLayout.from_profile(profile).names)
    piezo = [n for n in names if n != "screen"]
    lay = Layout.from_profile(profile)
    out = []
    for s in specs:
        if s.kind != "amp_monitor":
            continue
        ch = s.source or (piezo[0] if piezo else "")
        if ch not in piezo:
            raise UserError(
                f"[audio_inputs.{s.name}] source = {s.source!r}: not a piezo output channel; "
                f"name one of {', '.join(piezo)}"
            )
        patch = next((p for p in PATCHES if lay.channel[p] == ch), None)
        if patch is None:
            raise UserError(f"[audio_inputs.{s.name}]: no patch is driven by channel {ch!r}")
        out.append((s, ch, patch))
    return out


def channel_gain(outputs: Any, spec: Any, patch: str) -> dict[str, float]:
    """One chirp on ``patch``'s path; the monitor's gain and median coherence."""
    # lazy: the runtime part loads on first use
    from console.plugin_api.runtime import capture

    fs = int(outputs.limits.sample_rate_hz)
    x = record_v(CHIRP, fs)
    seg = Segment(x, np.zeros_like(x), frozenset({patch}), False, f"monitor {spec.name}")
    cap = capture(outputs, OutputPlan(fs, (seg,), f"self-test monitor {spec.name}", 0.0))
    y = cap.physical(spec.name)[: x.size]
    f, h, coh = h1(x, y, fs)
    keep = (f >= CHIRP.band_hz[0]) & (f <= CHIRP.band_hz[1])
    return {"gain": float(np.median(np.abs(h[keep]))), "coherence": float(np.median(coh[keep]))}


def monitor_findings(
    gains: dict[str, float], lay: Layout, profile_gain: dict[str, float]
) -> list[Finding]:
    """Each monitored channel's gain -> findings (empty: healthy), one line with the fix."""
    out = []
    for ch, g in gains.items():
        k = lay.card_output.get(ch, "?")
        nominal = profile_gain.get(ch)
        if g < SILENT:
            out.append(
                Finding(
                    "dead_channel",
                    ch,
                    f"amplifier channel '{ch}' (card output {k}): its monitor reads nothing "
                    "while the gate sent a chirp: check the amplifier (power, mute) and the "
                    f"cable from the card's output {k}",
                )
            )
        elif abs(20 * math.log10(g)) > GAIN_DB:
            set_to = f" (gain {nominal * g:.0f} instead of {nominal:.0f}?)" if nominal else ""
            out.append(
                Finding(
                    "weak_channel" if g < 1 else "gain",
                    ch,
                    f"amplifier channel '{ch}' (card output {k}): it gives "
                    f"{20 * math.log10(g):+.1f} dB of what the gate sent{set_to}: set the "
                    "amplifier's gain to the profile's [amplifiers] value, or repair a weak "
                    "output stage",
                )
            )
    return out


def card_specs(outputs: Any) -> tuple:
    """The inputs the card has (a twin without [audio_inputs] offers its own): 10 ms of
    silence captured through the gate."""
    # lazy: the runtime part loads on first use
    from console.plugin_api.runtime import capture

    fs = int(outputs.limits.sample_rate_hz)
    x = np.zeros(fs // 100)
    seg = Segment(x, x.copy(), frozenset({PATCHES[0]}), False, "inputs probe")
    return capture(outputs, OutputPlan(fs, (seg,), "self-test inputs probe", 0.0)).specs


def run_monitor_selftest(outputs: Any, profile: Any, specs: tuple = ()) -> dict[str, Any]:
    """Every monitored amplifier channel checked: a report like ``run_selftest``'s."""
    t0 = time.perf_counter()
    chans = monitored(profile, specs or card_specs(outputs))
    if not chans:
        raise UserError(
            f"{profile.path}: no amp_monitor among [audio_inputs]: add [audio_inputs.mon] "
            "channel = 3, kind = 'amp_monitor', sensitivity = 0.005 (the divider ratio)"
        )
    gains, coh = {}, {}
    for spec, ch, patch in chans:
        got = channel_gain(outputs, spec, patch)
        gains[ch], coh[ch] = got["gain"], got["coherence"]
    lay = Layout.from_profile(profile)
    nominal = {ch: float(profile.get("amplifiers.piezo_gain") or 0) for ch in gains}
    found = monitor_findings(gains, lay, nominal)
    return {
        "sensor": "amp_monitor",
        "ok": not found,
        "saved": False,
        "paths": sorted(gains),
        "gain": {ch: round(g, 4) for ch, g in gains.items()},
        "coherence_median": [round(coh[ch], 3) for ch in sorted(coh)],
        "findings": [f.to_json() for f in found],
        "lines": [f.line for f in found] or ["every amplifier channel gives what the gate sent"],
        "elapsed_s": time.perf_counter() - t0,
    }
