"""Vibrotactile flow under a hand (paper 5.2.2, Figs. 11 and 14).

The hand covers a ``hand_mm`` square centred at C, divided into ``squares x squares``
squares of ``subgrid x subgrid`` points (FRFs interpolated there). At drive amplitude V
a square is *active* when at least half of its subgrid points vibrate ``3 JND`` above
the palm threshold at that frequency: ``q_s V >= X(f)``, with ``q_s`` the
``ceil(n/2)``-th largest subgrid displacement per volt of the square and
``X = threshold_palm(f) * 10^(3 jnd/20)``.

For a flow in direction d the axis of symmetry passes through C across the flow
(vertical for left/right, horizontal for up/down). Part 1 needs the trailing side (the
squares where the flow starts: left column for ``right``) active and its mirror image,
the leading side, entirely passive; part 2 the reverse. Squares on the axis are free. So
for each excitation and frequency a part is possible when ``max_A q > max_B q``
(A: the side to activate, B: its mirror) and ``X / max_A q`` is within the drive cap.
Among possible candidates the one with the largest margin ``20 log10(max_A q / max_B q)``
wins. Both parts then get the same level ``s`` dB above the 3-JND line at their strongest
active square (equal sensation), with ``s`` at most half of each part's margin so the
passive side stays below the line. ``up`` is increasing y (mm), ``right`` increasing x.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from console.plugin_api import DIRECTIONS, UserError, VibrationMap
from plugins.vibrotactile.interp import interpolate_lattice
from plugins.vibrotactile.tables import usable_bins
from plugins.vibrotactile.thresholds import Perception


def side_masks(direction: str, squares: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """(start side, end side) boolean masks (squares, squares) indexed [row(y), col(x)]."""
    lo = np.zeros((squares, squares), bool)
    hi = np.zeros((squares, squares), bool)
    if direction in ("left", "right"):
        lo[:, 0], hi[:, -1] = True, True
    elif direction in ("up", "down"):
        lo[0, :], hi[-1, :] = True, True
    else:
        raise UserError(f"--direction {direction!r}: use one of {', '.join(DIRECTIONS)}")
    # rows grow with y; "up" runs toward -y (console.core.types.DIRECTIONS_MM)
    return (lo, hi) if direction in ("right", "down") else (hi, lo)


_BAND: dict[tuple, tuple] = {}


def _band_frf(m: VibrationMap, keep: np.ndarray) -> np.ndarray:
    """The map's FRFs at bins ``keep`` as complex64, cached per (map array, bins)."""
    key = (id(m.frf_um_per_v), keep.tobytes())
    hit = _BAND.get(key)
    if hit is not None and hit[0] is m.frf_um_per_v:
        return hit[1]
    arr = np.ascontiguousarray(m.frf_um_per_v[:, :, keep].astype(np.complex64))
    if len(_BAND) >= 4:
        _BAND.pop(next(iter(_BAND)))
    _BAND[key] = (m.frf_um_per_v, arr)
    return arr


def square_levels(
    m: VibrationMap,
    center_mm,
    *,
    hand_mm: float = 120.0,
    squares: int = 3,
    subgrid: int = 15,
    band_hz: float = 650.0,
    method: str = "spline",
    stride: int = 1,
    bins: np.ndarray | None = None,
    cache_bins: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """``q`` (E, squares, squares, K) um/V and the bin indices (K,) into ``m.freq_hz``.

    ``stride`` > 1 keeps every stride-th subgrid point per direction (a fast screen).
    ``cache_bins``: keep the FRFs at ``bins`` prepared in memory (bins reused per region).
    """
    keep = usable_bins(m, band_hz) if bins is None else np.asarray(bins)
    cx, cy = (float(v) for v in center_mm)
    sub = hand_mm / (squares * subgrid)
    local = np.arange(subgrid)[stride // 2 :: stride]
    n = local.size
    offs = (
        (np.arange(squares)[:, None] * subgrid + local[None, :]).ravel() + 0.5
    ) * sub - hand_mm / 2
    reuse = bins is None or cache_bins
    frf = _band_frf(m, keep) if reuse else m.frf_um_per_v[:, :, keep].astype(np.complex64)
    h = interpolate_lattice(m, cx + offs, cy + offs, method, frf=frf, cache=reuse)
    amp = np.abs(h)  # (E, S*n, S*n, K) float32
    e, _, _, k = amp.shape
    amp = (
        amp.reshape(e, squares, n, squares, n, k)
        .transpose(0, 1, 3, 2, 4, 5)
        .reshape(e, squares, squares, n * n, k)
    )
    rank = math.ceil(n * n / 2)  # at least half the points
    q = -np.partition(-amp, rank - 1, axis=3)[:, :, :, rank - 1]
    return q, keep


def part_scores(
    q: np.ndarray, side_a: np.ndarray, side_b: np.ndarray, x_um: np.ndarray, cap_v: float
):
    """(margin_db (E, K) with -inf where impossible, max_A q, max_B q)."""
    qa = q[:, side_a].max(axis=1)
    qb = q[:, side_b].max(axis=1)
    with np.errstate(divide="ignore"):
        margin = 20 * np.log10(qa / np.maximum(qb, 1e-30))
    ok = (qa > qb) & (x_um[None, :] / np.maximum(qa, 1e-30) <= cap_v)
    return np.where(ok, margin, -np.inf), qa, qb


def choose(
    q: np.ndarray,
    keep: np.ndarray,
    m: VibrationMap,
    direction: str,
    perception: Perception,
    cap_v: float,
    *,
    top: int = 0,
) -> dict:
    """The two parts for ``direction`` from square levels ``q``; ``top`` > 0 also returns
    the ``top`` best candidate bins per part (for exact re-scoring after a screen)."""
    squares = q.shape[1]
    start, end = side_masks(direction, squares)
    f = m.freq_hz[keep]
    x_um = perception.threshold_um(f, "palm") * 10 ** (3 * perception.jnd_db / 20)
    parts, cands = [], []
    for a, b in ((start, end), (end, start)):
        score, qa, qb = part_scores(q, a, b, x_um, cap_v)
        flat = int(np.argmax(score))
        e, k = np.unravel_index(flat, score.shape)
        if top:
            order = np.argsort(score, axis=None)[::-1][:top]
            cands.extend(keep[np.unravel_index(order, score.shape)[1]].tolist())
        if not np.isfinite(score[e, k]):
            parts.append(None)
            continue
        parts.append(
            {
                "actuator": m.excitations[e],
                "frequency_hz": float(f[k]),
                "margin_db": float(score[e, k]),
                "qa": float(qa[e, k]),
                "qb": float(qb[e, k]),
                "x_um": float(x_um[k]),
                "e": int(e),
                "k": int(k),
            }
        )
    out = {
        "direction": direction,
        "ok": all(p is not None for p in parts),
        "candidates": sorted(set(cands)),
    }
    if not out["ok"]:
        which = [i + 1 for i, p in enumerate(parts) if p is None]
        out["reason"] = (
            f"part {which[0]}: no excitation/frequency makes the {('start', 'end')[which[0] - 1]} side "
            f"active with its mirror passive within {cap_v:g} V"
        )
        out["parts"] = [p for p in parts if p is not None]
        return out
    s = min(min(p["margin_db"] / 2, 20 * np.log10(cap_v * p["qa"] / p["x_um"])) for p in parts)
    for p in parts:
        v = p["x_um"] / p["qa"] * 10 ** (s / 20)
        p["amplitude_v"] = float(v)
        p["active"] = (q[p["e"], :, :, p["k"]] * v >= p["x_um"]).tolist()
    out["level_above_3jnd_db"] = float(s)
    out["parts"] = parts
    return out


def screen_levels(
    m: VibrationMap,
    center_mm,
    *,
    screen_stride: int = 3,
    screen_df_hz: float = 0.5,
    **kw,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Stage 1 of ``staged_levels`` (it does not depend on the direction): square levels
    at every bin ~``screen_df_hz`` apart on every ``screen_stride``-th subgrid point.
    Returns (q, their bins, the usable bins, the bin step)."""
    keep = usable_bins(m, kw.get("band_hz", 650.0))
    df = float(np.median(np.diff(m.freq_hz[keep]))) if keep.size > 1 else 1.0
    step = max(1, int(round(screen_df_hz / df)))
    q, bins = square_levels(
        m, center_mm, stride=screen_stride, bins=keep[::step], cache_bins=True, **kw
    )
    return q, bins, keep, step


def refine_levels(
    m: VibrationMap,
    center_mm,
    screened: tuple,
    directions,
    perception: Perception,
    cap_v: float,
    *,
    screen_stride: int = 3,
    top: int = 8,
    final_top: int = 3,
    **kw,
) -> tuple[np.ndarray, np.ndarray]:
    """Stages 2 and 3 of ``staged_levels`` for ``directions`` from stage 1's ``screened``
    (``screen_levels``): one screen serves every direction of a place."""
    q, bins, keep, step = screened

    def candidates(q: np.ndarray, bins: np.ndarray, n: int) -> set:
        """The ``n`` best bins per part, over every direction asked for."""
        return {
            b
            for d in directions
            for b in choose(q, bins, m, d, perception, cap_v, top=n)["candidates"]
        }

    cand = candidates(q, bins, top)
    if step > 1:
        pos = np.searchsorted(keep, sorted(cand))
        near = np.unique(
            np.clip(pos[:, None] + np.arange(-step + 1, step)[None, :], 0, keep.size - 1)
        )
        q, bins = square_levels(m, center_mm, stride=screen_stride, bins=keep[near], **kw)
        cand = candidates(q, bins, final_top)
    return square_levels(m, center_mm, bins=np.array(sorted(cand)), **kw)


def staged_levels(
    m: VibrationMap,
    center_mm,
    directions,
    perception: Perception,
    cap_v: float,
    *,
    screen_stride: int = 3,
    screen_df_hz: float = 0.5,
    top: int = 8,
    final_top: int = 3,
    **kw,
) -> tuple[np.ndarray, np.ndarray]:
    """Square levels at the few bins worth scoring exactly, found in three stages:

    1. every bin ~``screen_df_hz`` apart (resonances are >= 2 zeta f wide, ~1 Hz at
       50 Hz for 1 % damping), every ``screen_stride``-th subgrid point: the ``top``
       candidates per part and direction;
    2. all bins within one screening step of those candidates, same sparse subgrid:
       the ``final_top`` best per part and direction;
    3. those bins on the full subgrid (exact levels), returned for ``choose``.
    """
    screened = screen_levels(
        m, center_mm, screen_stride=screen_stride, screen_df_hz=screen_df_hz, **kw
    )
    return refine_levels(
        m,
        center_mm,
        screened,
        directions,
        perception,
        cap_v,
        screen_stride=screen_stride,
        top=top,
        final_top=final_top,
        **kw,
    )


def search_levels(
    m: VibrationMap,
    center_mm,
    directions,
    perception: Perception,
    cap_v: float,
    *,
    screen_stride: int,
    screen_df_hz: float,
    top: int,
    **kw,
) -> tuple[np.ndarray, np.ndarray]:
    """Square levels to ``choose`` from: exhaustive (``square_levels``) when
    ``screen_stride`` is 1, else ``staged_levels`` for ``directions``."""
    if screen_stride > 1:
        return staged_levels(
            m,
            center_mm,
            directions,
            perception,
            cap_v,
            screen_stride=screen_stride,
            screen_df_hz=screen_df_hz,
            top=top,
            **kw,
        )
    return square_levels(m, center_mm, **kw)


def hand_flow(
    m: VibrationMap,
    center_mm,
    direction: str,
    perception: Perception,
    *,
    cap_v: float = 95.0,
    hand_mm: float = 120.0,
    squares: int = 3,
    subgrid: int = 15,
    band_hz: float = 650.0,
    method: str = "spline",
    screen_stride: int = 1,
    screen_df_hz: float = 0.5,
    top: int = 8,
) -> dict:
    """Flow under a hand at ``center_mm`` in ``direction``: the two parts and their
    active-square maps. ``screen_stride`` = 1: exhaustive (every bin, every subgrid
    point); > 1: ``staged_levels`` (what the whole-table sweep uses; the benchmark
    reports how often it matches the exhaustive choice)."""
    kw = dict(hand_mm=hand_mm, squares=squares, subgrid=subgrid, band_hz=band_hz, method=method)
    search = dict(screen_stride=screen_stride, screen_df_hz=screen_df_hz, top=top)
    q, keep = search_levels(m, center_mm, (direction,), perception, cap_v, **search, **kw)
    out = choose(q, keep, m, direction, perception, cap_v)
    out["center_mm"] = [float(c) for c in center_mm]
    out["hand_mm"] = hand_mm
    return out


def region_centers(m: VibrationMap, hand_mm: float, step_mm: float) -> np.ndarray:
    """Hand centres (N, 2) at ``step_mm`` steps where the hand lies inside the grid."""
    lo = m.points_mm.min(axis=0) + hand_mm / 2
    hi = m.points_mm.max(axis=0) - hand_mm / 2
    if np.any(hi < lo):
        raise UserError(f"a {hand_mm:g} mm hand does not fit inside the measured grid")
    xs = np.arange(lo[0], hi[0] + 1e-9, step_mm)
    ys = np.arange(lo[1], hi[1] + 1e-9, step_mm)
    return np.array([(x, y) for y in ys for x in xs])


def hand_flow_table(
    m: VibrationMap,
    perception: Perception,
    *,
    step_mm: float = 10.0,
    cap_v: float = 95.0,
    hand_mm: float = 120.0,
    squares: int = 3,
    subgrid: int = 15,
    band_hz: float = 650.0,
    method: str = "spline",
    screen_stride: int = 3,
    screen_df_hz: float = 0.5,
    top: int = 8,
    centers: np.ndarray | None = None,
    progress: Callable[[float, str], None] | None = None,
) -> dict:
    """Every region at ``step_mm`` steps, all four directions: arrays for a cache file.

    Returns ``centers_mm`` (N, 2), and per direction d (index in ``DIRECTIONS``):
    ``ok`` (N, 4), ``actuator`` (N, 4, 2) excitation index or -1, ``frequency_hz``,
    ``amplitude_v``, ``margin_db`` (N, 4, 2), ``active`` (N, 4, 2, S, S).
    """
    c = region_centers(m, hand_mm, step_mm) if centers is None else np.asarray(centers, float)
    n = len(c)
    ok = np.zeros((n, 4), bool)
    act = np.full((n, 4, 2), -1, np.int8)
    freq = np.full((n, 4, 2), np.nan)
    volt = np.full((n, 4, 2), np.nan)
    margin = np.full((n, 4, 2), np.nan)
    active = np.zeros((n, 4, 2, squares, squares), bool)
    kw = dict(hand_mm=hand_mm, squares=squares, subgrid=subgrid, band_hz=band_hz, method=method)
    search = dict(screen_stride=screen_stride, screen_df_hz=screen_df_hz, top=top)
    for i, cen in enumerate(c):
        q, keep = search_levels(m, cen, DIRECTIONS, perception, cap_v, **search, **kw)
        for j, d in enumerate(DIRECTIONS):
            r = choose(q, keep, m, d, perception, cap_v)
            ok[i, j] = r["ok"]
            if r["ok"]:
                for p_i, p in enumerate(r["parts"]):
                    act[i, j, p_i] = p["e"]
                    freq[i, j, p_i] = p["frequency_hz"]
                    volt[i, j, p_i] = p["amplitude_v"]
                    margin[i, j, p_i] = p["margin_db"]
                    active[i, j, p_i] = p["active"]
        if progress and (i % 10 == 0 or i == n - 1):
            progress((i + 1) / n, f"flow-under-hand maps {i + 1}/{n}")
    return {
        "centers_mm": c,
        "ok": ok,
        "actuator": act,
        "frequency_hz": freq,
        "amplitude_v": volt,
        "margin_db": margin,
        "active": active,
    }
