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

import numpy as np

from console.plugin_api import UserError, VibrationMap

from .grid import (
    Grid,
    bilinear_weights_1d,
    check_inside,
    grid_of,
    keys_weights_1d,
    spline_weights_1d,
)
from .modal_fit import modal_interpolate, modal_model

METHODS = ("bilinear", "keys", "spline", "modal")


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
    check_inside(xy[:, 0], grid.xs_mm, "x", extrapolate)
    check_inside(xy[:, 1], grid.ys_mm, "y", extrapolate)
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
    check_inside(xs, grid.xs_mm, "x", extrapolate)
    check_inside(ys, grid.ys_mm, "y", extrapolate)
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
    if frf is not None and frf is not m.frf_um_per_v:
        raise UserError(
            "interpolation method 'modal' synthesises the map's own bins; it takes no "
            "band-limited FRF copy (use bilinear, keys or spline here)"
        )
    grid = grid_of(m)
    xy = np.atleast_2d(np.asarray(xy_mm, float))
    check_inside(xy[:, 0], grid.xs_mm, "x", extrapolate)
    check_inside(xy[:, 1], grid.ys_mm, "y", extrapolate)
    h = modal_interpolate(modal_model(m), xy, m.freq_hz)
    h[..., m.masked] = 0.0  # masked bins carry no data: as the other methods give them
    return h
