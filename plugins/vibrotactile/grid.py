"""The measurement grid a vibration map's points form, and the 1-D interpolation weights
along one of its axes (bilinear, Keys' cubic convolution, not-a-knot spline): the pieces
``interp`` and ``modal_fit`` share."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.interpolate import make_interp_spline

from console.plugin_api import UserError, VibrationMap

TOL_MM = 1e-6


@dataclass(frozen=True)
class Grid:
    """The map's points as a full rectangular grid: ``index[r, c]`` is a map point index."""

    xs_mm: np.ndarray  # (C,) ascending
    ys_mm: np.ndarray  # (R,) ascending
    index: np.ndarray  # (R, C) int


def grid_of(m: VibrationMap) -> Grid:
    """Recognise the rectangular grid the map's points form (any point order)."""
    xs = np.unique(np.round(m.points_mm[:, 0], 6))
    ys = np.unique(np.round(m.points_mm[:, 1], 6))
    if xs.size * ys.size != m.points.size or xs.size < 2 or ys.size < 2:
        raise UserError(
            f"vibration map: its {m.points.size} points do not form a full rectangular grid "
            f"({xs.size} x-positions, {ys.size} y-positions); interpolation needs one"
        )
    c = np.searchsorted(xs, np.round(m.points_mm[:, 0], 6))
    r = np.searchsorted(ys, np.round(m.points_mm[:, 1], 6))
    index = np.full((ys.size, xs.size), -1)
    index[r, c] = np.arange(m.points.size)
    if (index < 0).any():
        raise UserError(
            "vibration map: points do not fill the rectangular grid; a point is missing"
        )
    return Grid(xs, ys, index)


def check_inside(v: np.ndarray, knots: np.ndarray, axis: str, extrapolate: bool) -> None:
    """Raise ``UserError`` for a coordinate outside the knots (unless ``extrapolate``)."""
    if extrapolate:
        return
    lo, hi = knots[0] - TOL_MM, knots[-1] + TOL_MM
    bad = (v < lo) | (v > hi)
    if bad.any():
        val = float(v[bad][0])
        shown = f"{val:.1f}" if abs(val) < 1e6 else f"{val:.3g}"
        raise UserError(
            f"point {axis}={shown} mm is outside the measured grid ({axis} {knots[0]:.1f}.."
            f"{knots[-1]:.1f} mm); pick a point inside or allow extrapolation (--extrapolate)"
        )


def bilinear_weights_1d(knots: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(N, K) linear-interpolation weights; outside the knots the end value is held."""
    v = np.clip(np.asarray(v, float), knots[0], knots[-1])
    j = np.clip(np.searchsorted(knots, v, side="right") - 1, 0, knots.size - 2)
    t = (v - knots[j]) / (knots[j + 1] - knots[j])
    w = np.zeros((v.size, knots.size))
    rows = np.arange(v.size)
    w[rows, j] = 1 - t
    w[rows, j + 1] += t
    return w


def keys_weights_1d(knots: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(N, K) weights of Keys' cubic convolution (a = -1/2): local, 4 knots per point,
    O(h^3); past the ends the missing knot is Keys' extrapolation 3f0 - 3f1 + f2."""
    v = np.clip(np.asarray(v, float), knots[0], knots[-1])
    k = knots.size
    j = np.clip(np.searchsorted(knots, v, side="right") - 1, 0, k - 2)
    t = (v - knots[j]) / (knots[j + 1] - knots[j])
    taps = np.stack(
        [
            (-(t**3) + 2 * t**2 - t) / 2,
            (3 * t**3 - 5 * t**2 + 2) / 2,
            (-3 * t**3 + 4 * t**2 + t) / 2,
            (t**3 - t**2) / 2,
        ],
        axis=1,
    )
    w = np.zeros((v.size, k))
    rows = np.arange(v.size)
    for i, off in enumerate((-1, 0, 1, 2)):
        idx = j + off
        lo, hi = idx < 0, idx > k - 1
        mid = ~(lo | hi)
        np.add.at(w, (rows[mid], idx[mid]), taps[mid, i])
        for side, base, step in ((lo, 0, 1), (hi, k - 1, -1)):
            if side.any():
                for c, knot in ((3, base), (-3, base + step), (1, base + 2 * step)):
                    np.add.at(w, (rows[side], np.full(side.sum(), knot)), c * taps[side, i])
    return w


@lru_cache(maxsize=64)
def _spline_basis(knots: tuple[float, ...], k: int):
    x = np.asarray(knots)
    return make_interp_spline(x, np.eye(x.size), k=min(k, x.size - 1))


def spline_weights_1d(knots: np.ndarray, v: np.ndarray, k: int = 3) -> np.ndarray:
    """(N, K) weights of the not-a-knot spline of degree ``k`` through the knots."""
    return _spline_basis(tuple(float(x) for x in knots), k)(np.asarray(v, float), extrapolate=True)
