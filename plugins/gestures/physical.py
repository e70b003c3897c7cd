"""Gesture features in physical units: what a hand's touching skin shows on the glass in
mm, and how it moves in mm (per 1/60 s), the same on any rear-DI image of a hand.

Per frame (``physical_static``): for a hand lying flat on the glass, the touching
skin's area, its largest region and its outline's solidity (closed against spread
fingers); for one above it, the number of fingertip-sized regions and the spacing of
the two largest of them and of all (not their size, which light that clips grows; and
no outline feature, as how much of a hovering palm is seen depends on the light's
falloff); pieces of one fingertip closer than a finger's width are one (``merge_pieces``).
Over a decision window
(``physical_motion``): the fingertips (or a flat hand's touching skin) followed
through the frames, each track's least-squares line less what the hand's jitter
explains (``beyond_jitter``; the tracks' residuals pooled, ``pooled``): their common shift, largest / smallest / mean displacement, the
largest raw end-to-end one, turn, arc, change of spacing, radial motion and how many
of them moved beyond a tremor, how many more or fewer fingertips the last frame shows
than the first (fingertips that met or parted: a pile's merging into fewer regions), and
the second and third largest of the tracks' displacements (a drag moves one fingertip, a
zoom or rotate two, a spread or pile all: at a slow start every one of them may stay under
the tremor floor the count of moving tracks is taken at, and their ranks still tell). A
fingertip is where its far end from the palm is
(``touch.far_ends``), not its contact's centroid, which a finger pressed flatter moves. Motion is
scaled to 60 fps (a gesture filmed at 48 fps moves 60/48 as far per frame);
``motion_view`` is what the classifiers see of it, and ``motion_shares`` how a motion
divides among shift, arc and change of spacing (its kind at any speed).

The hand's scale never enters: lengths are in mm through the frame's ``px_per_mm``
(``touch.default_px_per_mm`` or the camera's calibration).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import cv2
import numpy as np

#: a hand whose touching skin exceeds this (mm^2) lies flat on the glass: a flat hand
#: touches with 4000-16000 mm^2 on three renderers; five fingertips whose plateaus clip
#: under bright light (each taking in the finger just above the glass) reach 2400
FLAT_MM2 = 3000.0
#: fingertip-sized regions: within these areas (mm^2) and at least this share of the
#: largest such region (a curled finger's knuckle brushing the glass is smaller); a
#: light touch, or skin that a camera's optics shrink by a pixel, shows 20-40 mm^2;
#: under light that clips, a fingertip's plateau takes in the finger just above the
#: glass (600-1000 mm^2 at x1.3 on the silhouette renderer)
TIP_MM2 = (20.0, 1500.0)
TIP_SHARE = 0.3
#: touching regions followed through the frames: at most this far between frames at
#: 60 fps (mm)
TRACK_GATE_MM = 25.0
REFERENCE_FPS = 60.0
#: the columns of ``physical_static`` and ``physical_motion``
STATIC_NAMES = (
    "touch_mm2_log", "largest_mm2_log", "tips", "top2_spacing_mm", "max_spacing_mm",
    "flat", "flat_solidity",
)  # fmt: skip
MOTION_NAMES = (
    "shift_mm", "tracks", "track_dmax_mm", "track_dmin_mm", "track_dmean_mm",
    "track_end_mm", "track_turn_deg", "track_arc_mm", "track_spacing_mm",
    "track_radial_mm", "tracks_moving", "tips_met", "track_d2_mm", "track_d3_mm",
)  # fmt: skip
N_PHYS_STATIC = len(STATIC_NAMES)
N_PHYS_MOTION = len(MOTION_NAMES)
#: index of the fingertip count in ``physical_static`` (the classifiers get it as a
#: category too) and of the flat flag
COUNT_INDEX = 2
FLAT_INDEX = 5
#: the fingertips' columns of ``physical_static`` (their count and spacings)
TIP_COLUMNS = (2, 3, 4)


def physical_record(hand, extras: dict, touch: dict) -> dict:
    """The physical part of a frame record from a ``Hand``, its extras and its touching
    skin (``touch.hand_touch``): the touching regions (area mm^2, x mm, y mm in the
    camera's frame), the touching area, and the outline's solidity."""
    ppm = float(extras.get("px_per_mm") or 0.86)
    regions = np.asarray(touch.get("regions", np.zeros((0, 3))), float).reshape(-1, 3)
    regions = np.column_stack([regions[:, 0], regions[:, 1:] / ppm]).reshape(-1, 3)
    solidity = 0.0
    pts = np.asarray(hand.contour_px, np.float32).reshape(-1, 1, 2)
    if len(pts) >= 3 and float(touch.get("area_mm2", 0.0)) >= FLAT_MM2:  # only used then
        hull = cv2.contourArea(cv2.convexHull(pts))
        solidity = float(cv2.contourArea(pts) / hull) if hull > 0 else 0.0
    return {
        "touch_mm2": float(touch.get("area_mm2", 0.0)),
        "regions_mm": regions,
        "solidity": solidity,
    }


def similarity(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Least-squares b ~ s R a + t for 2-D point sets: (t, rotation rad, log scale)."""
    ca, cb = a.mean(0), b.mean(0)
    t = cb - ca
    if len(a) < 2:
        return t, 0.0, 0.0
    za = (a - ca) @ np.array([1, 1j])
    zb = (b - cb) @ np.array([1, 1j])
    den = float(np.sum(np.abs(za) ** 2))
    if den < 1e-9:
        return t, 0.0, 0.0
    s = complex(np.sum(np.conj(za) * zb)) / den
    if abs(s) < 1e-9:
        return t, 0.0, 0.0
    return t, math.atan2(s.imag, s.real), math.log(abs(s))


def _spacings(xy: np.ndarray) -> np.ndarray:
    if len(xy) < 2:
        return np.zeros(0)
    d = np.sqrt(((xy[:, None, :] - xy[None, :, :]) ** 2).sum(-1))
    return d[np.triu_indices(len(xy), 1)]


#: touching regions whose centres are closer than this (mm) are one fingertip seen in
#: pieces: two fingertips side by side are a finger's width apart (14-20 mm; the twin's
#: two_finger 23 mm and more), a fingertip split by a dim band or by its own clipped
#: plateau shows pieces 5 mm apart
TIP_APART_MM = 10.0


def merge_pieces(reg: np.ndarray, apart_mm: float = TIP_APART_MM) -> np.ndarray:
    """(k, 3) regions (area mm^2, x mm, y mm), largest first, with those whose centres
    are closer than ``apart_mm`` to a larger one joined into it (areas summed, the
    centre area-weighted)."""
    if len(reg) < 2:
        return reg
    d = np.sqrt(((reg[:, None, 1:] - reg[None, :, 1:]) ** 2).sum(-1))
    if not (d[np.triu_indices(len(reg), 1)] < apart_mm).any():
        return reg  # the usual frame: nothing to join
    order = np.argsort(-reg[:, 0], kind="stable")
    kept: list[list[int]] = []
    for i in order:
        for group in kept:
            if d[group[0], i] < apart_mm:
                group.append(int(i))
                break
        else:
            kept.append([int(i)])
    out = np.array([[reg[g, 0].sum(), *(reg[g, 0] @ reg[g, 1:] / reg[g, 0].sum())] for g in kept])
    return out[np.argsort(-out[:, 0], kind="stable")]


def tips_mm(rec: dict) -> np.ndarray:
    """(k, 2) mm: the fingertip-sized touching regions of a frame record, largest first
    (pieces of one fingertip joined: ``merge_pieces``)."""
    reg = merge_pieces(rec["regions_mm"])
    a = reg[:, 0]
    ok = (a >= TIP_MM2[0]) & (a <= TIP_MM2[1])
    if ok.any():
        ok &= a >= TIP_SHARE * a[ok].max()
    return reg[ok, 1:]


def is_flat(rec: dict) -> bool:
    """A hand lying flat on the glass (palm and fingers touching)."""
    return rec["touch_mm2"] >= FLAT_MM2


def physical_static(rec: dict | None) -> np.ndarray:
    """One frame's touching skin in mm (see the module's docstring); zeros without a
    hand."""
    v = np.zeros(N_PHYS_STATIC)
    if rec is None or "regions_mm" not in rec:
        return v
    if is_flat(rec):  # no fingertips: how a flat hand's skin splits into pads varies
        area = rec["regions_mm"][:, 0]
        v[0] = math.log1p(rec["touch_mm2"])
        v[1] = math.log1p(float(area.max())) if len(area) else 0.0
        v[5] = 1.0
        v[6] = rec["solidity"]
        return v
    # fingertips: how many and how far apart, not how large (light that clips grows
    # them to the finger just above the glass)
    tips = tips_mm(rec)
    sp = _spacings(tips)
    v[2] = min(len(tips), 6)
    v[3] = float(np.linalg.norm(tips[0] - tips[1])) if len(tips) > 1 else 0.0
    v[4] = float(sp.max()) if len(sp) else 0.0
    return v


def _points(rec: dict, flat: bool) -> np.ndarray:
    """What is followed: the fingertips, or a flat hand's touching skin as a whole (its
    area-weighted centroid: how the palm's touching skin splits into pieces varies)."""
    if not flat:
        return tips_mm(rec)
    reg = rec["regions_mm"]
    if not len(reg):
        return np.zeros((0, 2))
    return (reg[:, :1].T @ reg[:, 1:] / reg[:, 0].sum()).reshape(1, 2)


def _tracks(recs: Sequence[dict], gate_mm: float) -> list[np.ndarray]:
    """Touching regions followed through the records, a frame missed here and there:
    (m, 3) tracks of (frame, x mm, y mm) seen in the first and the last record: a flat
    hand's touching skin as a whole (``_flat_track``), else the fingertips, or, when none
    of them is followed through (fingertips gathered into one region too large for one,
    as a pile starts under light that clips), every touching region."""
    flat = sum(is_flat(r) for r in recs) * 2 > len(recs)  # one choice for the window
    if flat:
        return _flat_track(recs, gate_mm)
    return _follow(recs, tips_mm, gate_mm) or _follow(
        recs, lambda r: r["regions_mm"][:, 1:], gate_mm
    )


def _follow(recs: Sequence[dict], points, gate_mm: float) -> list[np.ndarray]:
    """The ``points(rec)`` ((k, 2) mm) of the records matched from frame to frame
    (least total distance, within ``gate_mm`` per frame): the tracks seen in the first
    and the last record."""
    from scipy.optimize import linear_sum_assignment  # lazy: scipy is slow to import

    tracks = [[(0, *p)] for p in points(recs[0])]
    for f, rec in enumerate(recs[1:], start=1):
        cur = points(rec)
        if not tracks or not len(cur):
            continue
        last = np.array([t[-1][1:] for t in tracks])
        gap = np.array([f - t[-1][0] for t in tracks], float)
        # each track's gate grows with the frames since it was last seen
        d = np.sqrt(((last[:, None, :] - cur[None, :, :]) ** 2).sum(-1)) / gap[:, None]
        for i, j in zip(*linear_sum_assignment(d), strict=True):
            if d[i, j] <= gate_mm:
                tracks[i].append((f, *cur[j]))
    n = len(recs) - 1
    return [np.array(t) for t in tracks if t[-1][0] == n]


#: pads whose displacements agree within this (mm) move together
AGREE_MM = 2.0


def consensus_shift(moves: np.ndarray) -> np.ndarray:
    """The displacement most of ``moves`` ((m, 2) mm) agree on within ``AGREE_MM``:
    the mean of the largest agreeing group (a pad that split or merged moves its
    centroid its own way; the pads that stay whole move with the hand)."""
    d = np.sqrt(((moves[:, None, :] - moves[None, :, :]) ** 2).sum(-1))
    near = d <= AGREE_MM
    best = int(np.argmax(near.sum(1) - 1e-6 * np.linalg.norm(moves, axis=1)))
    return moves[near[best]].mean(0)


def _flat_track(recs: Sequence[dict], gate_mm: float) -> list[np.ndarray]:
    """A flat hand's touching skin as one track: from frame to frame, the displacement
    its pads matched within ``gate_mm`` agree on (``consensus_shift``: pads that flicker
    in and out, split or merge move the skin's centroid by millimetres; the pads that
    stay whole do not), summed from the first frame's centroid."""
    from scipy.optimize import linear_sum_assignment  # lazy: scipy is slow to import

    start = _points(recs[0], True)
    if not len(start):
        return []
    pos, track = start[0].copy(), [(0, *start[0])]
    prev = recs[0]["regions_mm"][:, 1:]
    for f, rec in enumerate(recs[1:], start=1):
        cur = rec["regions_mm"][:, 1:]
        if not len(cur) or not len(prev):
            prev = cur if len(cur) else prev
            continue
        d = np.sqrt(((prev[:, None, :] - cur[None, :, :]) ** 2).sum(-1))
        i, j = linear_sum_assignment(d)
        ok = d[i, j] <= gate_mm
        if ok.any():
            pos = pos + consensus_shift(cur[j[ok]] - prev[i[ok]])
            track.append((f, *pos))
        prev = cur
    n = len(recs) - 1
    return [np.array(track)] if track[-1][0] == n else []


#: how many standard errors of a fitted displacement are taken as jitter
JITTER_Z = 1.5


def trend(f: np.ndarray, y: np.ndarray, n: int) -> tuple[np.ndarray, float]:
    """Least-squares line through ``y`` ((m,) or (m, d)) at frames ``f``: its change
    from frame 0 to ``n``, and that change's standard error from the residuals (0 with
    fewer than 3 points: no residual to judge jitter by)."""
    y = np.asarray(y, float).reshape(len(f), -1)
    if len(f) < 3:
        return y[-1] - y[0], 0.0
    coef, res, *_ = np.linalg.lstsq(np.c_[f, np.ones(len(f))], y, rcond=None)
    resid = y - np.c_[f, np.ones(len(f))] @ coef
    sigma = math.sqrt(float((resid**2).sum()) / (y.shape[1] * max(len(f) - 2, 1)))
    sxx = float(((f - f.mean()) ** 2).sum())
    return coef[0] * n, sigma * n / math.sqrt(sxx)


def pooled(fits: list, tracks: list[np.ndarray], n: int) -> list:
    """The tracks' fits (``trend``) with each standard error from the jitter all of them
    show about their lines (their residuals pooled): one hand's fingertips tremble
    alike, and a track's own two or three residuals may by chance show next to none."""
    ss = dof = 0.0
    sxx = []
    for (_, se), t in zip(fits, tracks, strict=True):
        f = t[:, 0]
        sx = float(((f - f.mean()) ** 2).sum())
        sxx.append(sx)
        if len(f) >= 3 and n > 0:
            ss += (se * math.sqrt(sx) / n) ** 2 * (len(f) - 2)
            dof += len(f) - 2
    if dof == 0:
        return fits
    sigma = math.sqrt(ss / dof)
    return [(c, sigma * n / math.sqrt(sx) if sx > 0 else 0.0) for (c, _), sx in
            zip(fits, sxx, strict=True)]  # fmt: skip


def beyond_jitter(change: float, se: float) -> float:
    """A fitted change less what the window's own jitter explains (``JITTER_Z``
    standard errors): a trembling hand's random steps shrink to 0, a steady motion
    keeps nearly all of its length."""
    return max(abs(change) - JITTER_Z * se, 0.0)


def physical_motion(records: Sequence[dict | None], fps: float = REFERENCE_FPS) -> np.ndarray:
    """How the touching skin moved over the records, mm at 60 fps, beyond the jitter
    each track shows about its own least-squares line (see the module's docstring);
    zeros with fewer than two hands."""
    v = np.zeros(N_PHYS_MOTION)
    recs = [r for r in records if r is not None and "regions_mm" in r]
    if len(recs) < 2:
        return v
    k = fps / REFERENCE_FPS  # mm at this frame rate -> mm at 60 fps
    n = len(recs) - 1
    tracks = _tracks(recs, TRACK_GATE_MM / max(k, 0.5))
    v[1] = min(len(tracks), 6)
    if not any(is_flat(r) for r in recs):
        # fingertips that met or parted over the window (a pile's tips merging into fewer
        # regions, a pinch closing): how many more or fewer the window's last two frames
        # both show than its first two (a region seen in one frame only, a knuckle
        # brushing the glass, is no fingertip)
        counts = [len(tips_mm(r)) for r in recs]
        v[11] = abs(min(counts[-2:]) - min(counts[:2]))
    if not tracks:
        return v
    fits = pooled([trend(t[:, 0], t[:, 1:], n) for t in tracks], tracks, n)
    a = np.array([t[0, 1:] if len(t) < 3 else t[:, 1:].mean(0) for t in tracks])
    moved = np.array([f[0].ravel() for f in fits])
    a = a - moved * (np.array([t[:, 0].mean() for t in tracks]) / max(n, 1))[:, None]
    b = a + moved
    disp = np.array([beyond_jitter(float(np.linalg.norm(d)), se) for d, (_, se) in
                     zip(moved, fits, strict=True)])  # fmt: skip
    t, turn, _ = similarity(a, b)
    se_mean = float(np.mean([se for _, se in fits]))
    v[0] = k * beyond_jitter(float(np.linalg.norm(t)), se_mean / math.sqrt(len(fits)))
    v[2], v[3], v[4] = k * disp.max(), k * disp.min(), k * disp.mean()
    # how many of them moved beyond a tremor (a zoom moves two fingertips while curled
    # fingers rest on the glass; a spread or pile moves them all)
    v[10] = min(int(np.count_nonzero(k * disp > TREMOR_MM)), 6)
    ranked = np.sort(k * disp)[::-1]
    v[12], v[13] = (ranked[i] if len(ranked) > i else 0.0 for i in (1, 2))
    v[5] = k * max(float(np.linalg.norm(tr[-1, 1:] - tr[0, 1:])) for tr in tracks)
    if len(tracks) >= 2:
        ra = np.linalg.norm(a - a.mean(0), axis=1)
        rb = np.linalg.norm(b - b.mean(0), axis=1)
        arc = abs(turn) * float(ra.mean())
        v[6] = k * abs(math.degrees(turn)) * beyond_jitter(arc, se_mean) / max(arc, 1e-9)
        v[7] = k * beyond_jitter(arc, se_mean)  # arc length at the regions
        v[8] = k * _spacing_change(tracks, n)
        v[9] = k * beyond_jitter(float(np.abs(rb - ra).mean()), se_mean)
    return v


def _spacing_change(tracks: list[np.ndarray], n: int) -> float:
    """The tracks' mean spacing: its fitted change over the frames all of them are
    seen in, beyond its jitter."""
    frames = set.intersection(*(set(t[:, 0].astype(int)) for t in tracks))
    f = np.array(sorted(frames), float)
    if len(f) < 2:
        return 0.0
    pos = [np.array([t[t[:, 0] == x, 1:][0] for t in tracks]) for x in f]
    change, se = trend(f, np.array([_spacings(p).mean() for p in pos]), n)
    return beyond_jitter(float(change[0]), se)


#: motion below this is tremor (mm at 60 fps over a window, or degrees): the classifiers
#: see how far beyond it a hand moved, compressed (log), so a faster hand than the
#: training set's is read as moving, not as something else
TREMOR_MM = 1.5
TREMOR_DEG = 1.0


#: lengths the classifiers see whole (log-compressed, no tremor floor): each is already
#: beyond its own track's jitter, and a slow start's second and third fingertips move less
#: than the floor by the 4th frame (twin LOSO dynamic-only 0.924 -> 0.960 with them)
UNFLOORED = ("track_d2_mm", "track_d3_mm")


def motion_view(m: np.ndarray) -> np.ndarray:
    """(n, N_PHYS_MOTION) motion rows as the classifiers see them: each length and
    angle beyond the tremor floor, log-compressed (``UNFLOORED`` ones whole); the
    counts as they are."""
    m = np.atleast_2d(np.asarray(m, float))
    floor = np.full(N_PHYS_MOTION, TREMOR_MM)
    floor[MOTION_NAMES.index("track_turn_deg")] = TREMOR_DEG
    for name in UNFLOORED:
        floor[MOTION_NAMES.index(name)] = 0.0
    out = np.log1p(np.maximum(m - floor, 0.0))
    for i in (MOTION_NAMES.index(k) for k in ("tracks", "tracks_moving", "tips_met")):
        out[:, i] = m[:, i]
    return out


#: the parts of a motion whose shares tell its kind: common shift, arc, change of spacing
SHARE_PARTS = ("shift_mm", "track_arc_mm", "track_spacing_mm")
#: below this (mm at 60 fps) a motion's shares fade to 0 (a trembling hand has no kind)
SHARE_SOFT_MM = 1.0


def motion_shares(m: np.ndarray) -> np.ndarray:
    """(n, 3): how a motion divides among ``SHARE_PARTS`` (each over their sum plus
    ``SHARE_SOFT_MM``): the same for a zoom at any speed (its spacing's share near 1), a
    rotate (the arc's) or a drag (the shift's), where the lengths themselves depend on
    how fast the people of the training set moved."""
    m = np.atleast_2d(np.asarray(m, float))
    parts = np.abs(m[:, [MOTION_NAMES.index(k) for k in SHARE_PARTS]])
    return parts / (parts.sum(axis=1, keepdims=True) + SHARE_SOFT_MM)


def physical_score(motion: np.ndarray) -> float:
    """How far the hand's touching skin moved (mm at 60 fps): its regions' largest
    displacement."""
    return float(motion[2])
