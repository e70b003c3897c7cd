"""FRF interpolation from the measurement grid to any point on the glass.

Both methods are linear in the data: an interpolated FRF is ``sum_p w_p(x, y) H_p(f)``
with real weights applied to the complex FRFs (real and imaginary parts, never
magnitudes: a nodal line between two grid points must come out near zero, not as the
mean of two magnitudes). The weights are tensor products of 1-D weights in x and y.

- ``bilinear``: the paper's method. Exact at grid points; error grows as (k h)^2, with k
  the bending wavenumber and h = 60 mm (FACTS: ~6 %, 17 %, 35 % at 100, 300, 625 Hz).
- ``keys``: Keys' cubic convolution, local (4 x 4 grid points), error ~ (k h)^3: a
  faster middle ground when only a few points are needed per query.
- ``spline`` (default): not-a-knot cubic spline along x and y (``scipy``
  ``make_interp_spline``, k = 3). Error ~ (k h)^4; best measured on the analytic plate
  (see ``haptable bench vibration``).
- ``modal``: a fitted modal model (``modal_fit``: sdypy-EMA LSCF poles, LSFD residues)
  whose residue fields are interpolated in a plate-mode basis (standing waves + edge
  terms, spline for the remainder): a better spatial basis than the spline's cubics, so
  it wins where k h is large (300-625 Hz) and on noisy maps; it costs a fit per map
  (8-16 s CPU on 2 cores, cached) and works on points only (not ``interpolate_lattice``).

Points outside the grid rectangle raise ``UserError`` unless ``extrapolate=True``
(bilinear: nearest edge value held constant; spline: the end polynomial pieces, so
accuracy decays with distance; at half a pitch outside it is still usable, at the plate
edge it is not reliable: see the tests).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.interpolate import make_interp_spline

from console.errors import UserError
from console.vibration_map import VibrationMap

METHODS = ("bilinear", "keys", "spline", "modal")
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


def _check_inside(v: np.ndarray, knots: np.ndarray, axis: str, extrapolate: bool) -> None:
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


def weights_1d(knots: np.ndarray, v: np.ndarray, method: str) -> np.ndarray:
    if method == "bilinear":
        return bilinear_weights_1d(knots, v)
    if method == "spline":
        return spline_weights_1d(knots, v, 3)
    if method == "spline5":
        return spline_weights_1d(knots, v, 5)
    if method == "keys":
        return keys_weights_1d(knots, v)
    raise UserError(f"interpolation method {method!r} is unknown; use one of {', '.join(METHODS)}")


def point_weights(
    grid: Grid,
    xy_mm: np.ndarray,
    method: str = "spline",
    *,
    extrapolate: bool = False,
    n_points: int,
) -> np.ndarray:
    """(N, P) weights mapping the map's P points to N query points."""
    xy = np.atleast_2d(np.asarray(xy_mm, float))
    _check_inside(xy[:, 0], grid.xs_mm, "x", extrapolate)
    _check_inside(xy[:, 1], grid.ys_mm, "y", extrapolate)
    wx = weights_1d(grid.xs_mm, xy[:, 0], method)  # (N, C)
    wy = weights_1d(grid.ys_mm, xy[:, 1], method)  # (N, R)
    w = np.zeros((xy.shape[0], n_points))
    w[:, grid.index.ravel()] = (wy[:, :, None] * wx[:, None, :]).reshape(xy.shape[0], -1)
    return w


_PREPARED: dict[tuple, tuple] = {}  # explicit cache keyed by the identity of the FRF array


def _prepared(
    frf: np.ndarray, layout: str, grid: Grid | None = None, cache: bool = True
) -> np.ndarray:
    """The FRFs rearranged for real-valued BLAS products, cached per array object.

    ``points``: (P, E*F*2) float (real/imag interleaved); ``grid``: (E, R, C, F*2) float.
    The cache holds a reference to ``frf``, so its id cannot be reused while cached.
    """
    key = (id(frf), layout)
    hit = _PREPARED.get(key)
    if hit is not None and hit[0] is frf:
        return hit[1]
    if layout == "points":
        arr = (
            np.ascontiguousarray(frf.transpose(1, 0, 2))
            .view(frf.real.dtype)
            .reshape(frf.shape[1], -1)
        )
    else:
        arr = np.ascontiguousarray(frf[:, grid.index]).view(frf.real.dtype)
    if not cache:
        return arr
    if len(_PREPARED) >= 8:
        _PREPARED.pop(next(iter(_PREPARED)))
    _PREPARED[key] = (frf, arr)
    return arr


def interpolate(
    m: VibrationMap,
    xy_mm: np.ndarray,
    method: str = "spline",
    *,
    extrapolate: bool = False,
    frf: np.ndarray | None = None,
) -> np.ndarray:
    """Complex FRFs (E, N, F) in um/V at points ``xy_mm`` (N, 2).

    ``frf`` may pass a band-limited copy of the map's FRFs (E, P, F') to work on.
    """
    if method == "modal":
        return _modal(m, xy_mm, extrapolate, frf)
    h = m.frf_um_per_v if frf is None else frf
    w = point_weights(grid_of(m), xy_mm, method, extrapolate=extrapolate, n_points=m.points.size)
    cols = np.flatnonzero(np.any(w != 0, axis=0))  # bilinear: 4 points per query point
    out = (w[:, cols].astype(h.real.dtype) @ _prepared(h, "points")[cols]).view(h.dtype)  # (N, E*F)
    return out.reshape(w.shape[0], h.shape[0], h.shape[2]).transpose(1, 0, 2)


def interpolate_lattice(
    m: VibrationMap,
    xs_mm: np.ndarray,
    ys_mm: np.ndarray,
    method: str = "spline",
    *,
    extrapolate: bool = False,
    frf: np.ndarray | None = None,
    cache: bool = True,
) -> np.ndarray:
    """Complex FRFs (E, Ny, Nx, F') on the lattice ``ys x xs`` (separable: fast).

    ``frf`` may pass a band-limited copy of the map's FRFs (E, P, F') to work on.
    """
    if method == "modal":
        raise UserError(
            "interpolation method 'modal' gives FRFs at points (tables query, stimuli); flows "
            "under a hand use bilinear, keys or spline"
        )
    grid = grid_of(m)
    xs, ys = np.asarray(xs_mm, float), np.asarray(ys_mm, float)
    _check_inside(xs, grid.xs_mm, "x", extrapolate)
    _check_inside(ys, grid.ys_mm, "y", extrapolate)
    h = m.frf_um_per_v if frf is None else frf
    hr = _prepared(h, "grid", grid, cache)  # (E, R, C, 2F) real
    dt = hr.dtype
    wx = weights_1d(grid.xs_mm, xs, method).astype(dt)  # (Nx, C)
    wy = weights_1d(grid.ys_mm, ys, method).astype(dt)  # (Ny, R)
    e, r, _, f2 = hr.shape
    a = np.matmul(wx, hr)  # (E, R, Nx, 2F)
    b = np.matmul(wy, a.reshape(e, r, -1))  # (E, Ny, Nx*2F)
    return b.reshape(e, ys.size, xs.size, f2).view(h.dtype)


def _modal(m: VibrationMap, xy_mm, extrapolate: bool, frf: np.ndarray | None) -> np.ndarray:
    """``interpolate`` by the map's fitted modal model (fitted once per map content)."""
    from .modal_fit import modal_interpolate, modal_model

    if frf is not None and frf is not m.frf_um_per_v:
        raise UserError(
            "interpolation method 'modal' synthesises the map's own bins; it takes no "
            "band-limited FRF copy (use bilinear, keys or spline here)"
        )
    grid = grid_of(m)
    xy = np.atleast_2d(np.asarray(xy_mm, float))
    _check_inside(xy[:, 0], grid.xs_mm, "x", extrapolate)
    _check_inside(xy[:, 1], grid.ys_mm, "y", extrapolate)
    h = modal_interpolate(modal_model(m), xy, m.freq_hz)
    h[..., m.masked] = 0.0  # masked bins carry no data: as the other methods give them
    return h
