"""FRF interpolation vs the exact analytic plate: grid points, off-grid error by band,
nodal lines (complex, never magnitudes), edges and outside points."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.errors import UserError
from plugins.vibrotactile.interp import interpolate, interpolate_lattice


def rel_err(h, ref, sel):
    return np.linalg.norm(h[..., sel] - ref[..., sel]) / np.linalg.norm(ref[..., sel])


@pytest.mark.parametrize("method", ["bilinear", "keys", "spline"])
def test_exact_at_grid_points(ss_map, method):
    h = interpolate(ss_map, ss_map.points_mm[[0, 11, 50, 83]], method)
    np.testing.assert_allclose(h, ss_map.frf_um_per_v[:, [0, 11, 50, 83]], atol=1e-12)


def test_off_grid_error_by_band(ss_plate, ss_map):
    rng = np.random.default_rng(0)
    xy = np.column_stack([rng.uniform(41.73, 701.73, 120), rng.uniform(43.645, 403.645, 120)])
    ref = ss_plate.frf_um_per_v(xy, ss_map.freq_hz)
    f = ss_map.freq_hz
    bands = [(5, 150), (150, 300), (300, 450), (450, 625)]
    bil = [
        rel_err(interpolate(ss_map, xy, "bilinear"), ref, (f >= lo) & (f < hi)) for lo, hi in bands
    ]
    spl = [
        rel_err(interpolate(ss_map, xy, "spline"), ref, (f >= lo) & (f < hi)) for lo, hi in bands
    ]
    assert all(s < b / 2 for s, b in zip(spl, bil, strict=True))  # the spline is the better one
    assert bil[-1] > 0.10  # bilinear on a 6 cm grid: tens of % near 600 Hz (FACTS ~35 %)
    assert max(spl) < 0.06


def test_nodal_line_interpolates_complex_not_magnitude(ss_plate, ss_map):
    """x = a/2 is a nodal line of mode (2,1) and lies midway between grid columns 6 and 7."""
    f = ss_map.freq_hz
    k = int(np.argmin(np.abs(f - 97.06)))  # mode (2,1) resonance
    xy = np.array([[ss_plate.a_mm / 2, 223.645]])
    exact = abs(ss_plate.frf_um_per_v(xy, f[k : k + 1], ("PA",))[0, 0, 0])
    got = abs(interpolate(ss_map, xy, "bilinear")[0, 0, k])
    left, right = (
        np.abs(interpolate(ss_map, xy + [[dx, 0]], "bilinear")[0, 0, k]) for dx in (-30, 30)
    )
    magnitude_mean = (left + right) / 2  # what interpolating magnitudes would claim
    assert magnitude_mean > 5 * max(got, exact)
    assert got == pytest.approx(exact, abs=0.2 * magnitude_mean)


def test_grid_edge_is_inside_plate_edge_is_outside(ss_plate, ss_map):
    on_grid_edge = np.array([[41.73, 200.0]])
    h = interpolate(ss_map, on_grid_edge, "spline")
    ref = ss_plate.frf_um_per_v(on_grid_edge, ss_map.freq_hz)
    assert rel_err(h, ref, ss_map.freq_hz < 300) < 0.05
    plate_edge = np.array([[0.0, 200.0]])
    with pytest.raises(UserError, match=r"x=0.0 mm is outside the measured grid"):
        interpolate(ss_map, plate_edge)
    ext = interpolate(ss_map, plate_edge, "spline", extrapolate=True)  # documented, not reliable
    assert np.all(np.isfinite(ext))
    held = interpolate(ss_map, plate_edge, "bilinear", extrapolate=True)
    np.testing.assert_allclose(held, interpolate(ss_map, on_grid_edge, "bilinear"))


def test_lattice_equals_pointwise(ss_map):
    xs, ys = np.array([100.0, 233.3, 500.0]), np.array([90.0, 300.0])
    lat = interpolate_lattice(ss_map, xs, ys)
    pts = np.array([(x, y) for y in ys for x in xs])
    np.testing.assert_allclose(
        lat.reshape(5, -1, ss_map.freq_hz.size), interpolate(ss_map, pts), atol=1e-12
    )


def test_unknown_method(ss_map):
    with pytest.raises(UserError, match="unknown"):
        interpolate(ss_map, [[100.0, 100.0]], "cubic-magic")
