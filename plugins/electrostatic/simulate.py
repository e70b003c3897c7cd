"""Twin of the knob gesture: thumb/index contact trajectories and the offline pipeline.

``rotation_frames`` turns an index-finger angle profile into camera-rate contact frames
(thumb as pivot with a little drift, index on an arc), with position noise, fingers
lifting for a frame or two and contact-id swaps. ``run_pipeline`` drives tracker ->
knob -> stream in simulated time: before each audio block (``block`` samples) every frame
captured by then is processed, exactly what the live loop does.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from console.plugin_api import Contact

from .knob import Crossing
from .rotation import RotationState
from .session import KnobSession
from .settings import KNOB_DEFAULTS


def min_jerk(t_s: np.ndarray, t0_s: float, dur_s: float, a0: float, a1: float) -> np.ndarray:
    """Minimum-jerk move from ``a0`` to ``a1`` between ``t0_s`` and ``t0_s + dur_s``."""
    u = np.clip((np.asarray(t_s, dtype=float) - t0_s) / max(dur_s, 1e-9), 0.0, 1.0)
    return a0 + (a1 - a0) * (10 * u**3 - 15 * u**4 + 6 * u**5)


def rotation_frames(
    angle_deg: np.ndarray,
    t_s: np.ndarray,
    *,
    center_mm: tuple[float, float] = (370.0, 220.0),
    radius_mm: float = 50.0,
    base_deg: float = -30.0,
    noise_mm: float = 0.3,
    pivot_drift_mm: float = 1.0,
    lift_frames: Sequence[tuple[int, str, int]] = (),
    swap_frames: Sequence[int] = (),
    extra_contact_frames: Sequence[int] = (),
    rng: np.random.Generator | None = None,
) -> list[tuple[float, tuple[Contact, ...]]]:
    """Contact frames of a two-finger rotation following ``angle_deg`` (deg) at ``t_s``.

    ``lift_frames``: (frame, "thumb"|"index"|"both", n_frames) lifts; ``swap_frames``:
    frames from which the two contact ids (and list order) are exchanged.
    """
    rng = rng or np.random.default_rng(0)
    a = np.radians(np.asarray(angle_deg, dtype=float) + base_deg)
    n = len(a)
    drift = pivot_drift_mm * np.stack(
        [np.sin(2 * np.pi * 0.3 * np.asarray(t_s)), np.cos(2 * np.pi * 0.2 * np.asarray(t_s))], 1
    )
    thumb = np.asarray(center_mm) + drift + rng.normal(0, noise_mm, (n, 2))
    index = (
        np.asarray(center_mm)
        + drift
        + radius_mm * np.stack([np.cos(a), np.sin(a)], 1)
        + rng.normal(0, noise_mm, (n, 2))
    )
    gone: dict[int, set[str]] = {}
    for f0, which, k in lift_frames:
        for f in range(f0, min(f0 + k, n)):
            gone.setdefault(f, set()).update({"thumb", "index"} if which == "both" else {which})
    swapped = np.zeros(n, dtype=bool)
    for f in swap_frames:
        swapped[f:] = ~swapped[f:]
    frames = []
    for i in range(n):
        cs = []
        ids = (2, 1) if swapped[i] else (1, 2)
        for name, pos, cid in (("thumb", thumb[i], ids[0]), ("index", index[i], ids[1])):
            if name not in gone.get(i, set()):
                p = (float(pos[0]), float(pos[1]))
                cs.append(Contact(id=cid, pos_px=p, pos_mm=p, area_px=80.0))
        if swapped[i]:
            cs.reverse()
        if i in extra_contact_frames:  # a palm or another finger touching far away
            p = (float(center_mm[0]) - 150.0, float(center_mm[1]) + 90.0)
            cs.append(Contact(id=9, pos_px=p, pos_mm=p, area_px=300.0))
        frames.append((float(t_s[i]), tuple(cs)))
    return frames


@dataclass
class PipelineResult:
    piezo_v: np.ndarray
    screen_v: np.ndarray
    sample_rate_hz: int
    block: int
    states: list[RotationState]
    crossings: list[Crossing]
    crossing_ids: list[int]
    detent_log: list[tuple[int, int]]
    trace: list[tuple[int, float, float]]
    items: list[int] = field(default_factory=list)  # selected item after each frame
    latency: np.ndarray = field(default_factory=lambda: np.zeros(0))  # samples, per crossing


def run_pipeline(
    frames: Sequence[tuple[float, Sequence[Any]]],
    condition: str,
    *,
    sample_rate_hz: int = 48000,
    block: int = 64,
    settings: Mapping[str, Any] | None = None,
    limits: Mapping[str, float] | None = None,
    sectors: int | None = None,
    start_item: int = 0,
    tail_s: float = 0.1,
) -> PipelineResult:
    """Frames -> tracker -> knob -> stream in simulated time, then a ramped stop.

    Blocks that start before a frame's time are rendered before the frame is processed
    (the audio callback runs on its own clock; a crossing lands in the next block).
    """
    s = {**KNOB_DEFAULTS, **(settings or {})}
    ses = KnobSession(
        condition,
        sectors=int(sectors or s["sectors"]),
        settings=s,
        limits=limits,
        sample_rate_hz=sample_rate_hz,
        block=block,
        start_item=start_item,
    )
    for t, cs in frames:
        ses.render_until(t)
        ses.feed(t, cs)
    ses.render_until((frames[-1][0] if frames else 0.0) + tail_s)
    ses.finish()
    piezo, screen = ses.output()
    return PipelineResult(
        piezo,
        screen,
        sample_rate_hz,
        block,
        ses.states,
        ses.crossings,
        ses.crossing_ids,
        list(ses.stream.detent_log),
        list(ses.stream.trace),
        ses.items,
        ses.latency_samples(),
    )


def canned_rotation(fps: float = 60.0, seed: int = 0) -> list[tuple[float, tuple[Contact, ...]]]:
    """A ~4 s rotation for auditions: 270 deg forward at varying speed, a pause, 90 back."""
    t = np.arange(0, 4.0, 1 / fps)
    ang = min_jerk(t, 0.3, 1.6, 0.0, 270.0) + min_jerk(t, 2.4, 1.0, 0.0, -90.0)
    return rotation_frames(ang, t, noise_mm=0.2, rng=np.random.default_rng(seed))


def instantaneous_freq_hz(x: np.ndarray, sample_rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-crossing frequency estimate: (time of each half period s, frequency Hz)."""
    x = np.asarray(x, dtype=float)
    s = np.signbit(x)
    idx = np.nonzero(s[1:] != s[:-1])[0]
    if idx.size < 2:
        return np.zeros(0), np.zeros(0)
    # linear interpolation of each crossing instant
    x0, x1 = x[idx], x[idx + 1]
    tz = (idx + x0 / (x0 - x1)) / sample_rate_hz
    half = np.diff(tz)
    return 0.5 * (tz[1:] + tz[:-1]), 1.0 / (2.0 * half)
