"""What every closed-loop check shares: the default pairs and regions, the loop's
settings, the profile's measured map and registered effects, and one plan played through
the safety gate with the plate twin's envelopes read from what was actually played (the
RECORDING and the relay log)."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from console.plugin_api import (
    ChannelLayout,
    FlowPatchDrives,
    HandFlowGeometry,
    UserError,
    VibrationMap,
    make_map,
)

from .closed_loop import drive_from_recording, part_envelopes

if TYPE_CHECKING:
    from console.plugin_api import Plugins, Profile

#: Pairs (grid numbers, active -> passive) checked by default: the paper's 51/52 example
#: both ways, diagonal neighbours as in Fig. 10's pairs 1-1, 3-3, 4-4, and a long pair.
DEFAULT_PAIRS: tuple[tuple[int, int], ...] = (
    (51, 52),
    (52, 51),
    (27, 40),
    (40, 27),
    (62, 75),
    (19, 32),
    (14, 71),
)
#: Hand regions (centre mm): four spots across the table (the paper's R1..R4 are only
#: drawn, not given in numbers), each with the four directions.
DEFAULT_REGIONS: tuple[tuple[float, float], ...] = (
    (180.0, 280.0),
    (300.0, 160.0),
    (460.0, 290.0),
    (580.0, 150.0),
)


@dataclass(frozen=True)
class LoopSettings:
    part_s: float = 1.5
    ramp_ms: float = 100.0
    settle_s: float = 0.2  # after the ramp before the steady stretch (lowest mode's tau)
    pre_s: float = 0.05  # recording kept before the first part (plate at rest)


def measured_map(profile: Profile, plugins: Plugins, progress: Any = None) -> VibrationMap:
    """The profile's vibration map measured by its ``[vibrometer] driver`` (twin default),
    built by ``plugins``."""
    name = str(profile.get("vibrometer.driver", "twin"))
    dev = plugins.get("vibrometer", name).factory(profile)
    out = dev.measure(progress=progress)
    return make_map(**{k: v for k, v in out.items() if k != "meta"})


def relay_channels_of(profile) -> dict[str, int]:
    return {
        n: int(p["relay_channel"])
        for n, p in profile.items("patches").items()
        if p.get("relay_channel")
    }


def loop_profile(profile, ls: LoopSettings):
    """The profile with the flow parts' length and ramp of ``ls`` (``[vibrotactile]
    part_s`` / ``ramp_ms``); everything else as the profile says."""
    vt = {**profile.section("vibrotactile"), "part_s": ls.part_s, "ramp_ms": ls.ramp_ms}
    return replace(profile, data={**profile.data, "vibrotactile": vt})


def effects_of(profile: Profile, plugins: Plugins, ls: LoopSettings | None = None) -> tuple:
    """The effects ``plugins`` register that drive two-point flows and flows under a
    hand patch by patch (``FlowPatchDrives``, ``HandFlowGeometry``: asked by capability,
    built fresh), for ``profile`` with ``ls``'s part length."""
    prof = loop_profile(profile, ls or LoopSettings())
    hint = "vibrotactile"
    return (
        plugins.provider("effect", FlowPatchDrives, prof, plugin_hint=hint, fresh=True),
        plugins.provider("effect", HandFlowGeometry, prof, plugin_hint=hint, fresh=True),
    )


def recording_with_offset(outputs, tries: int = 200) -> tuple[np.ndarray, int]:
    """The outputs' recording and the clock of its first sample.

    The twin keeps the last ``record_s`` seconds; the clock of its first sample is
    (blocks played x block size) - its length, read when the outputs are idle and the
    block count is stable around the read.
    """
    if outputs.recording() is None:
        raise UserError(
            "closed loop: these outputs record nothing (real hardware); use a profile whose "
            "[audio] driver is the twin"
        )
    for _ in range(tries):
        time.sleep(0.002)
        st = outputs.status()
        if st["busy"]:
            continue
        b1 = st["audio"].get("blocks")
        rec = outputs.recording()
        b2 = outputs.status()["audio"].get("blocks")
        if b1 is not None and b1 == b2:
            return rec, int(b1) * int(st["audio"]["block_size"]) - rec.shape[0]
    raise RuntimeError("outputs never went idle: cannot align the recording with its clock")


def play_and_envelope(
    outputs, profile, twin, plan, points_mm, ls: LoopSettings, peak_points, freqs_hz
):
    """Play ``plan`` through the gate, then the twin's envelopes per part at the points."""
    report = outputs.play(plan)
    fs = plan.sample_rate_hz
    start = max(0, report.segment_start[0] - int(ls.pre_s * fs))
    stop = report.segment_end[-1] + int(0.5 * fs)
    rec, clock0 = recording_with_offset(outputs)
    v, w = drive_from_recording(
        rec,
        outputs.relay_log(),
        relay_channels_of(profile),
        start,
        stop,
        clock0,
        ChannelLayout.from_profile(profile).names,
    )
    parts = [
        (s - start, e - start)
        for s, e in zip(report.segment_start, report.segment_end, strict=True)
    ]
    return part_envelopes(
        twin,
        v,
        w,
        points_mm,
        fs,
        parts,
        ramp_s=ls.ramp_ms / 1e3,
        settle_s=ls.settle_s,
        freqs_hz=freqs_hz,
        peak_points=peak_points,
    )


def one_blas_thread():
    """Thin matrix products throughout: one BLAS thread is fastest (and on a loaded
    2-core machine, multi-threaded BLAS is 10x slower)."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")
