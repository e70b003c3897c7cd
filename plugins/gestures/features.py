"""Gesture features from the vision pipeline's per-frame results.

Every decision is made from the first ``n`` frames of a gesture (the model's
``n_frames``, the same window for each part). The feature rows keep everything the
pipeline measures (the canonical silhouette's Fourier descriptors, zero columns where a
brightness grid was (kept in the layout, no longer measured), the finger count, the contacts' layout in palm radii, the hand's motion in palm radii,
and the touching skin in mm and its motion, ``physical``); the classifiers see the
columns that mean the same on any rear-DI image (``select_static``, ``select_dynamic``,
``select_kind``): the touching skin in mm, its motion in mm at 60 fps, and the Fourier
magnitudes of a hand lying flat. ``motion_score`` is the touching regions' largest
displacement (mm). The number of fingertips is given to the classifiers as a category
as well (``count_code``): one finger or two is what tells some gestures apart.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from .hand_shape import GRID_RINGS, GRID_SECTORS
from .physical import (
    COUNT_INDEX,
    FLAT_INDEX,
    MOTION_NAMES,
    N_PHYS_MOTION,
    N_PHYS_STATIC,
    REFERENCE_FPS,
    TIP_COLUMNS,
    motion_shares,
    motion_view,
    physical_motion,
    physical_record,
    physical_score,
    physical_static,
    similarity,
)
from .vision import FrameResult, VisionParams, process_frame, vision_params

N_GRID = GRID_SECTORS * (len(GRID_RINGS) - 1)
N_CONTACT = 6
TRACK_GATE = 1.5  # palm radii a contact may move between frames and stay the same
MOTION_TURN_DEG = 20.0  # a turn of this many degrees counts as one palm radius of motion
#: harmonics the features are built with (a model selects its own ``n_harmonics`` of them)
N_HARMONICS_MAX = 16
#: decision windows (the first k frames) features are kept for
FRAMES_LIST = (2, 3, 4, 5, 6)


def desc_size(n_harmonics: int) -> int:
    return 3 * (2 * n_harmonics - 1)


def desc_indices(n: int, n_max: int, parts: tuple[int, ...] = (0, 1, 2)) -> np.ndarray:
    """Indices, in a descriptor vector of ``n_max`` harmonics, of the one with ``n``
    (``n = 0``: none); ``parts``: 0 real, 1 imaginary, 2 magnitude blocks."""
    if n < 2:
        return np.zeros(0, dtype=int)
    ks = np.concatenate([np.arange(-n_max, 0), np.arange(2, n_max + 1)])
    keep = np.flatnonzero(np.abs(ks) <= n)
    m = len(ks)
    return np.concatenate([keep + p * m for p in parts])


def static_size(n_harmonics: int) -> int:
    return desc_size(n_harmonics) + N_GRID + 2 + N_CONTACT + N_PHYS_STATIC


#: the hand's scale (palm radius, px) is never taken below this: a smaller palm on the
#: 640 x 480 view is a palm above the glass too dim to segment whole (pointing poses
#: under another light falloff: 9-20 px on the phalanx renderer, 32-50 px on the twin
#: for the same poses), and contacts and motion measured in it would be renderer-bound
MIN_PALM_PX = 30.0


def frame_record(res: FrameResult) -> dict | None:
    """The main (largest) hand of a frame, compactly; None if there is no hand. Its
    scale (``palm_radius_px``) is at least ``MIN_PALM_PX``, the contacts' canonical
    positions in that scale."""
    if not res.hands:
        return None
    h, ex = res.hands[0], res.extras[0]
    pr = float(ex["palm_radius_px"])
    scale = max(pr, MIN_PALM_PX)
    return {
        "palm_px": np.asarray(ex["palm_px"], dtype=float),
        "palm_radius_px": scale,
        "bright_px": np.asarray(ex["bright_px"], dtype=float),
        "angle_deg": float(h.angle_deg),
        "descriptors": np.asarray(h.descriptors, dtype=float),
        # the brightness grid's columns stay in the layout, zero: no classifier reads
        # them (``select_*``), and the vision no longer spends 0.26 ms a frame on them
        "grid": np.zeros(N_GRID),
        "fingers": int(h.finger_count),
        "contacts_px": np.array([c.pos_px for c in h.contacts], dtype=float).reshape(-1, 2),
        "contacts_canon": np.asarray(ex["contacts_canon"], dtype=float).reshape(-1, 2)
        * (pr / scale),
        **physical_record(h, ex, res.touch.of(0) if res.touch is not None else {}),
    }


def contact_layout(canon: np.ndarray) -> np.ndarray:
    """Contacts in the canonical frame (palm radii): count, mean distance from the palm,
    largest pairwise distance, mean |x|, mean y, angular spread (rad)."""
    k = len(canon)
    if k == 0:
        return np.zeros(N_CONTACT)
    r = np.hypot(canon[:, 0], canon[:, 1])
    pair = 0.0
    if k > 1:
        d = canon[:, None, :] - canon[None, :, :]
        pair = float(np.sqrt((d**2).sum(-1)).max())
    ang = np.sort(np.arctan2(canon[:, 1], canon[:, 0]))
    spread = 0.0
    if k > 1:
        gaps = np.diff(np.concatenate([ang, [ang[0] + 2 * math.pi]]))
        spread = float(2 * math.pi - gaps.max())
    return np.array(
        [
            min(k, 8),
            r.mean(),
            pair,
            np.abs(canon[:, 0]).mean(),
            canon[:, 1].mean(),
            spread,
        ]
    )


def record_static(rec: dict | None, n_harmonics: int) -> np.ndarray:
    """Static feature vector of one frame record (zeros and a flag if no hand)."""
    size = static_size(n_harmonics)
    if rec is None:
        v = np.zeros(size)
        v[desc_size(n_harmonics) + N_GRID + 1] = -1.0  # finger count -1: no hand
        return v
    return np.concatenate(
        [
            rec["descriptors"],
            rec["grid"],
            [rec["fingers"], 1.0],
            contact_layout(rec["contacts_canon"]),
            physical_static(rec),
        ]
    )


def static_features(records: Sequence[dict | None], n_harmonics: int, n_frames: int = 4):
    """Mean static features over the first ``n_frames`` frames that show a hand; the
    fingertips' count and spacings their median over those frames (a region flickering
    into one frame of four, a knuckle brushing the glass, is no fingertip)."""
    recs = [r for r in records[:n_frames] if r is not None]
    if not recs:
        return record_static(None, n_harmonics)
    rows = np.array([record_static(r, n_harmonics) for r in recs])
    out = rows.mean(axis=0)
    tips = static_size(n_harmonics) - N_PHYS_STATIC + np.array(TIP_COLUMNS)
    out[tips] = np.median(rows[:, tips], axis=0)
    return out


def _match(a: np.ndarray, b: np.ndarray, gate: float) -> list[tuple[int, int]]:
    """Pairs (i, j) of points of ``a`` and ``b`` matched by minimum total distance."""
    if len(a) == 0 or len(b) == 0:
        return []
    from scipy.optimize import linear_sum_assignment

    d = np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1))
    ri, ci = linear_sum_assignment(d)
    return [(int(i), int(j)) for i, j in zip(ri, ci, strict=True) if d[i, j] <= gate]


def contact_tracks(records: Sequence[dict | None], gate_px: float) -> list[np.ndarray]:
    """Contacts followed through every frame: list of (n_frames, 2) pixel tracks."""
    if not records or any(r is None for r in records):
        return []
    tracks = {i: [p] for i, p in enumerate(records[0]["contacts_px"])}
    alive = {i: i for i in tracks}  # track id -> index in the current frame
    for rec in records[1:]:
        cur = rec["contacts_px"]
        ids = list(alive)
        last = np.array([tracks[t][-1] for t in ids]).reshape(-1, 2)
        pairs = _match(last, cur, gate_px)
        nxt = {}
        for i, j in pairs:
            tracks[ids[i]].append(cur[j])
            nxt[ids[i]] = j
        alive = nxt
    n = len(records)
    return [np.array(t) for t in tracks.values() if len(t) == n]


def _wrap_deg(d: float) -> float:
    return (d + 180.0) % 360.0 - 180.0


N_MOTION = 22 + N_PHYS_MOTION
#: the contacts' |log| change of scale among the motion features
ZOOM_INDEX = 14


def motion_features(records: Sequence[dict | None], fps: float = REFERENCE_FPS) -> np.ndarray:
    """How the hand and its contacts moved over the records (palm radii, degrees; then
    ``physical.physical_motion``: mm at 60 fps)."""
    recs = [r for r in records if r is not None]
    v = np.zeros(N_MOTION)
    v[22:] = physical_motion(recs, fps)
    if len(recs) < 2:
        return v
    r0, r1 = recs[0], recs[-1]
    rp = max(r0["palm_radius_px"], 1.0)
    t = math.radians(r0["angle_deg"])
    rot = np.array([[math.cos(t), math.sin(t)], [-math.sin(t), math.cos(t)]])
    d_hand = rot @ (r1["palm_px"] - r0["palm_px"]) / rp
    turn = _wrap_deg(r1["angle_deg"] - r0["angle_deg"])
    steps = [
        np.linalg.norm(b["palm_px"] - a["palm_px"]) / rp
        for a, b in zip(recs, recs[1:], strict=False)
    ]
    v[0:2] = np.abs(d_hand)
    v[2] = np.linalg.norm(d_hand)
    v[3] = abs(turn) / MOTION_TURN_DEG
    v[4] = math.log(max(r1["palm_radius_px"], 1.0) / rp)
    v[5] = float(np.abs(r1["grid"] - r0["grid"]).sum())
    v[6] = float(np.mean(steps))
    n0, n1 = len(r0["contacts_px"]), len(r1["contacts_px"])
    v[7], v[8] = min(n0, 8), min(n1, 8)
    tracks = contact_tracks(recs, TRACK_GATE * rp)
    v[9] = len(tracks)
    if tracks:
        a = np.array([tr[0] for tr in tracks])
        b = np.array([tr[-1] for tr in tracks])
        tr_t, tr_rot, tr_scale = similarity(a, b)
        tt = rot @ tr_t / rp
        disp = np.array([np.linalg.norm(tr[-1] - tr[0]) for tr in tracks]) / rp
        path = np.array([np.linalg.norm(np.diff(tr, axis=0), axis=1).sum() for tr in tracks]) / rp
        v[10:12] = np.abs(tt)
        v[12] = np.linalg.norm(tt)
        v[13] = abs(math.degrees(tr_rot)) / MOTION_TURN_DEG
        v[14] = abs(tr_scale)  # zooming in and out alike
        v[15] = disp.max()
        v[16] = disp.min()
        v[17] = disp.min() / disp.max() if disp.max() > 1e-6 else 1.0
        v[18] = path.max()
    d_bright = rot @ (r1["bright_px"] - r0["bright_px"]) / rp
    v[19:21] = np.abs(d_bright)
    v[21] = float(max(np.linalg.norm(r["bright_px"] - r0["bright_px"]) for r in recs[1:]) / rp)
    return v


def motion_score(records: Sequence[dict | None], fps: float = REFERENCE_FPS) -> float:
    """How much the hand moved over the records: the larger of the displacement of its
    touching skin's centroid and of its touching regions (mm at 60 fps)."""
    return physical_score(physical_motion([r for r in records if r is not None], fps))


def dynamic_features(
    records: Sequence[dict | None], n_harmonics: int, n_frames: int = 4, fps: float = 60.0
) -> np.ndarray:
    """The static features over the window (``static_features``: the mean of its frames,
    as the static classifier sees them) with the most fingertips two of its frames show
    (fingertips that touch each other merge into one region as a pinch or a pile of
    fingers starts or ends, and a dim one may be missed in a frame; a region flickering
    into one frame is no fingertip; with two frames, the more of them), plus the motion
    over the first ``n_frames`` frames."""
    recs = list(records[:n_frames])
    static = static_features(recs, n_harmonics, n_frames)
    shown = [r for r in recs if r is not None]
    if shown:
        count = static_size(n_harmonics) - N_PHYS_STATIC + COUNT_INDEX
        counts = sorted(physical_static(r)[COUNT_INDEX] for r in shown)
        static[count] = counts[-2] if len(counts) >= 3 else counts[-1]
    return np.concatenate([static, motion_features(recs, fps)])


MAX_COUNT_CODE = 5


def count_code(counts: np.ndarray) -> np.ndarray:
    """(n,) contact counts (a mean over frames may lie between two) -> (n, 6) columns,
    one per count 0 .. ``MAX_COUNT_CODE``: 1 at the count, shared linearly between the two
    nearest for a fractional one (one-hot for whole counts; 5 and more share the last)."""
    c = np.clip(np.asarray(counts, dtype=float), 0, MAX_COUNT_CODE)
    k = np.arange(MAX_COUNT_CODE + 1)
    return np.maximum(0.0, 1.0 - np.abs(c[:, None] - k[None, :]))


def _phys_static_cols(n_max: int) -> np.ndarray:
    start = desc_size(n_max) + N_GRID + 2 + N_CONTACT
    return start + np.arange(N_PHYS_STATIC)


def select_static(x: np.ndarray, n: int, n_max: int) -> np.ndarray:
    """What the static classifier sees, from (n, static_size(n_max)) feature rows:
    magnitudes of ``n`` Fourier harmonics of a hand lying flat (invariant to mirroring
    as well; zeros for a hand above the glass, whose outline depends on how bright its
    hovering palm is) and the
    touching skin in mm (``physical.physical_static``), its fingertip-sized region
    count as a category too. Left and right hands look alike to it; nothing in it is
    measured in the hand's own scale."""
    x = np.atleast_2d(x)
    phys = x[:, _phys_static_cols(n_max)]
    flat = phys[:, FLAT_INDEX : FLAT_INDEX + 1]  # the outline only of a hand lying flat
    return np.concatenate(
        [flat * x[:, desc_indices(n, n_max, (2,))], phys, count_code(phys[:, COUNT_INDEX])],
        axis=1,
    )


def select_dynamic(x: np.ndarray, n: int, n_max: int) -> np.ndarray:
    """What the dynamic classifier sees, from (n, static_size(n_max) + N_MOTION) rows:
    Fourier magnitudes and touching skin over the window (as ``select_static``; the most
    fingertips two frames show, ``dynamic_features``) and
    the touching skin's motion in mm (``physical.physical_motion``), and the contacts'
    change of scale (|log|, no unit: it tells a zoom from a rotation on the twin's
    slow-starting gestures, LOSO dynamic 0.933 -> 0.960, and changes no cross-renderer
    result)."""
    x = np.atleast_2d(x)
    size = static_size(n_max)
    return np.concatenate(
        [
            select_static(x[:, :size], n, n_max),
            motion_view(x[:, size + 22 : size + N_MOTION]),
            motion_shares(x[:, size + 22 : size + N_MOTION]),
            x[:, size + ZOOM_INDEX : size + ZOOM_INDEX + 1],
        ],
        axis=1,
    )


def select_kind(x: np.ndarray) -> np.ndarray:
    """What the static/dynamic classifier sees, from (n, N_MOTION) motion rows: the
    touching skin's motion in mm (``physical.physical_motion``) but how many tracks moved
    beyond the tremor floor and the ranks of the fingertips' displacements (a count at a
    hard threshold: a model trained on fast starts learns "moving means at least one",
    and slow starts on another table fall below it; they tell gestures apart, not
    whether there is one); motion measured in
    the hand's own scale depends on how much of its hovering palm is seen."""
    return np.delete(motion_view(np.atleast_2d(x)[:, 22:N_MOTION]), _COUNTS, axis=1)


#: counts and ranks of fingertips that tell gestures apart, not whether there is one
_COUNTS = [
    MOTION_NAMES.index(k) for k in ("tracks_moving", "tips_met", "track_d2_mm", "track_d3_mm")
]


def sample_records(
    frames: np.ndarray,
    background: np.ndarray,
    params: VisionParams,
    times: list | None = None,
    cpu: list | None = None,
    clip: list | None = None,
) -> list[dict | None]:
    """Frame records of a sample's frames; the pipeline's wall time (and thread CPU
    time) of each frame is appended to ``times`` (and ``cpu``), its clipped and touching
    pixel counts to ``clip``."""
    out = []
    for img in frames:
        c0 = time.thread_time()
        t0 = time.perf_counter()
        res = process_frame(img, background, params)
        t1 = time.perf_counter()
        if times is not None:
            times.append(t1 - t0)
        if cpu is not None:
            cpu.append(time.thread_time() - c0)
        if clip is not None:
            clip.append((res.clipped_px, res.touching_px))
        out.append(frame_record(res))
    return out


def record_features(
    recs: list[dict | None],
    frames_list: Sequence[int],
    n_harmonics: int,
    fps: float = REFERENCE_FPS,
) -> tuple[dict[int, np.ndarray], dict[int, np.ndarray], dict[int, np.ndarray], dict[int, float]]:
    """Per decision window k in ``frames_list`` (the first k records, filmed at
    ``fps``): (static, kind, dynamic features, motion score)."""
    xs = {k: static_features(recs, n_harmonics, k) for k in frames_list}
    xk = {k: motion_features(recs[:k], fps) for k in frames_list}
    xd = {k: dynamic_features(recs, n_harmonics, k, fps) for k in frames_list}
    sc = {k: motion_score(recs[:k], fps) for k in frames_list}
    return xs, xk, xd, sc


def analysis_params(profile: Any) -> VisionParams:
    """The profile's vision settings with every harmonic the features keep (what
    datasets are analysed with: a model picks its own harmonics from them)."""
    return replace(vision_params(profile), n_harmonics=N_HARMONICS_MAX)
