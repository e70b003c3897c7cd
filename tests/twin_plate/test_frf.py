"""Piezo coupling and FRFs of the plate twin: analytic cases, direct solves, hard cases."""

from __future__ import annotations

import math
import warnings
from dataclasses import replace

import numpy as np
import pytest
from numpy.polynomial import legendre as leg

from plugins.twin.plate import frf, piezo, ritz
from plugins.twin.plate.model import build_twin, default_params, grid_points_mm


@pytest.fixture(scope="module")
def sim():
    return build_twin(default_params())


def test_pin_force_moment_is_of_the_expected_size():
    m = piezo.pin_force_moment(-180e-12, 0.2e-3, 62e9, 72e9, 3.18e-3)
    assert -0.03 < m < -0.01  # FACTS: about 0.02 N m/m per volt, sign of d31
    # a very stiff plate blocks the patch: F -> E_a t_a d31 V / t_a = E_a d31 V
    blocked = piezo.pin_force_moment(-180e-12, 0.2e-3, 62e9, 1e18, 1e-3)
    assert blocked == pytest.approx(62e9 * -180e-12 * (1e-3 + 0.2e-3) / 2, rel=1e-6)


def test_patch_load_equals_quadrature_of_the_laplacian():
    plate = ritz.Plate(0.74346, 0.44729, 3.18e-3, 72e9, 0.22, 2500.0)
    modes = ritz.solve_modes(plate, (7.5e6, 5.0), 16, f_max_hz=900)
    patch = piezo.PiezoPatch("PA", (20.0, 170.0), (35.0, 61.0))
    q = piezo.modal_forces(modes, piezo.patch_loads(modes.system, [patch], 1.0))[:, 0]
    x1, x2, y1, y2 = piezo.patch_rect_m(patch, plate.a_m, plate.b_m)
    g, wg = leg.leggauss(24)
    xs, ys = x1 + (g + 1) * (x2 - x1) / 2, y1 + (g + 1) * (y2 - y1) / 2
    xx, yy = (v.ravel() for v in np.meshgrid(xs, ys, indexing="ij"))
    ww = np.outer(wg, wg).ravel() * (x2 - x1) * (y2 - y1) / 4
    quad = ww @ modes.shapes(xx, yy, "lap")
    np.testing.assert_allclose(q, quad, rtol=1e-8, atol=1e-10 * np.abs(quad).max())


def test_patch_force_matches_analytic_ssss_and_symmetry_zeroes():
    a, b = 0.6, 0.4
    plate = ritz.Plate(a, b, 3e-3, 70e9, 0.3, 2500.0)
    modes = ritz.solve_modes(plate, "ssss", 18)
    # a patch centred on x = a/2 cannot drive modes antisymmetric about it (m even)
    patch = piezo.PiezoPatch("P", (300.0, 120.0), (60.0, 40.0))
    q = piezo.modal_forces(modes, piezo.patch_loads(modes.system, [patch], 1.0))[:, 0]
    x1, x2, y1, y2 = piezo.patch_rect_m(patch, a, b)
    rho_h = plate.mass_per_area
    for r, (m, n) in enumerate(((1, 1), (2, 1), (1, 2), (3, 1))):
        km, kn = m * math.pi / a, n * math.pi / b
        amp = 2 / math.sqrt(rho_h * a * b)  # mass-normalised sine amplitude
        ix = (math.cos(km * x1) - math.cos(km * x2)) / km
        iy = (math.cos(kn * y1) - math.cos(kn * y2)) / kn
        expected = -(km**2 + kn**2) * amp * ix * iy
        if m % 2 == 0:
            assert abs(q[r]) < 1e-9 * np.abs(q).max()
        else:
            assert abs(q[r]) == pytest.approx(abs(expected), rel=1e-6)


def test_patch_outside_the_plate_is_an_error():
    with pytest.raises(ValueError, match="outside"):
        piezo.patch_rect_m(piezo.PiezoPatch("PA", (900.0, 100.0), (35.0, 61.0)), 0.74, 0.44)


def _direct_frf(twin, x_mm, y_mm, freqs_hz):
    """Undamped harmonic solve (K - w^2 M) c = f in the whole Ritz space, um/V."""
    s = twin.modes.system
    loads = piezo.patch_loads(s, list(twin.params.patches), twin.params.moment_n_per_v)
    f = loads.reshape(4, -1).T
    vx = s.bx.values(2 * np.asarray(x_mm) / 1e3 / s.plate.a_m - 1)
    vy = s.by.values(2 * np.asarray(y_mm) / 1e3 / s.plate.b_m - 1)
    ev = np.einsum("pi,pj->pij", vx, vy).reshape(len(x_mm), -1)
    out = []
    for fr in freqs_hz:
        w2 = (2 * math.pi * fr) ** 2
        c = np.linalg.solve(s.k - w2 * s.m_scale * np.eye(s.k.shape[0]), f)
        out.append(ev @ c)
    return np.array(out).transpose(2, 1, 0) * 1e6  # (4, P, F)


def test_truncated_modal_frf_matches_direct_solve(sim):
    """Modes up to 2x band + static residual reproduce the full undamped solution."""
    undamped = replace(sim.params, damping_ratio=1e-9)
    x, y = grid_points_mm()
    pts = [0, 17, 50, 51, 83]
    fn = sim.freq_hz
    # frequencies between resonances (undamped FRFs are singular at them)
    freqs = np.array([0.5 * (fn[i] + fn[i + 1]) for i in (0, 3, 8, 15)] + [30.0, 600.0])
    direct = _direct_frf(sim, x[pts], y[pts], freqs)
    with_res = build_twin(undamped).frf_um_per_v(x[pts], y[pts], freqs)[:4]
    no_res = build_twin(replace(undamped, static_residual=False)).frf_um_per_v(
        x[pts], y[pts], freqs
    )[:4]
    scale = np.abs(direct).max()
    err_res = np.abs(with_res - direct).max() / scale
    err_none = np.abs(no_res - direct).max() / scale
    print(f"truncation vs direct: {err_res:.2e} with residual, {err_none:.2e} without")
    assert err_res < 5e-3
    assert err_res < 0.25 * err_none  # the residual removes most of the truncation error


def test_truncation_error_is_small_at_the_default_margin():
    from plugins.twin.plate.model import truncation_error

    rows = truncation_error(default_params(), margins=(1.0, 2.0), residual=(True,))
    assert rows[1]["max_rel"] < 5e-3 < rows[0]["max_rel"]


def test_sim_frf_peaks_are_of_the_expected_order(sim):
    x, y = grid_points_mm()
    h = sim.frf_um_per_v(x, y, np.arange(5.0, 625.0, 0.1))
    peaks = np.abs(h).max(axis=(1, 2))
    assert np.all((peaks > 0.05) & (peaks < 2.0)), peaks  # FACTS: 0.1-1 um/V
    first = sim.freq_hz
    assert 20 < first[0] < 120 and 8 <= np.sum(first < 625) <= 40


def test_pall_is_the_sum_of_the_four_patches(sim):
    x, y = grid_points_mm()
    h = sim.frf_um_per_v(x, y, np.array([123.4, 465.0]))
    np.testing.assert_allclose(h[4], h[:4].sum(axis=0), rtol=1e-10, atol=1e-14)


def test_mirror_patches_give_mirror_frfs(sim):
    """PA and PC are mirror images about x = a/2: so are their FRFs (paper, Fig. 6)."""
    a_mm = sim.params.plate.a_m * 1e3
    x, y = np.array([100.0, 300.0, 371.73]), np.array([60.0, 200.0, 400.0])
    f = np.array([94.0, 257.0, 465.0])
    h = sim.frf_um_per_v(x, y, f, ("PA",))
    h_mirror = sim.frf_um_per_v(a_mm - x, y, f, ("PC",))
    np.testing.assert_allclose(h, h_mirror, rtol=1e-8, atol=1e-12)


def test_direct_solve_with_modal_damping_matches_complex_modal_sum_for_close_modes():
    """Two modes closer than their half-power bandwidth add as complex numbers."""
    plate = ritz.Plate(0.5, 0.5 / 1.003, 3e-3, 70e9, 0.3, 2500.0)  # near-square CCCC
    zeta = 0.01
    modes = ritz.solve_modes(plate, "cccc", 14)
    f2, f3 = modes.freq_hz[1:3]
    assert abs(f3 - f2) < 2 * zeta * f2  # closer than the half-power bandwidth
    s = modes.system
    patch = piezo.PiezoPatch("P", (60.0, 90.0), (40.0, 30.0))
    load = piezo.patch_loads(s, [patch], 0.02).reshape(-1)
    phi = modes.coeffs.reshape(modes.coeffs.shape[0], -1)
    m = s.m_scale * np.eye(s.k.shape[0])
    c = m @ phi.T @ np.diag(2 * zeta * modes.omega_rad_s) @ phi @ m  # modal damping
    xp, yp = np.array([0.13]), np.array([0.31])
    ev = np.einsum(
        "pi,pj->pij", s.bx.values(2 * xp / 0.5 - 1), s.by.values(2 * yp / s.plate.b_m - 1)
    )
    freqs = np.linspace(f2 - 3 * zeta * f2, f3 + 3 * zeta * f3, 41)
    direct = []
    for fr in freqs:
        w = 2 * math.pi * fr
        direct.append(ev.reshape(1, -1) @ np.linalg.solve(s.k + 1j * w * c - w * w * m, load))
    direct = np.array(direct)[:, 0]
    q = phi @ load
    modal = frf.displacement_frf(modes.shapes(xp, yp), q[:, None], modes.omega_rad_s, freqs, zeta)
    np.testing.assert_allclose(modal[0, 0], direct, rtol=1e-8)
    # and not the sum of magnitudes: the merged peak differs from |H2| + |H3|
    g = frf.modal_receptance(modes.omega_rad_s[1:3], freqs, zeta)
    parts = modes.shapes(xp, yp)[0, 1:3, None] * q[1:3, None] * g
    assert np.abs(np.abs(parts).sum(0) - np.abs(parts.sum(0))).max() > 0.05 * np.abs(modal).max()


def test_light_damping_raises_peaks_tenfold():
    p = default_params()
    lo = build_twin(replace(p, damping_ratio=0.001))
    hi = build_twin(replace(p, damping_ratio=0.01))
    f1 = hi.freq_hz[0]
    x, y = np.array([371.73]), np.array([223.6])  # centre: the first mode's antinode
    peak_lo = np.abs(lo.frf_um_per_v(x, y, np.array([f1]), ("PALL",))).item()
    peak_hi = np.abs(hi.frf_um_per_v(x, y, np.array([f1]), ("PALL",))).item()
    assert 8.0 < peak_lo / peak_hi < 10.5


def test_points_on_the_edges_move_on_seals_and_not_on_simple_supports(sim):
    a, b = sim.params.plate.a_m * 1e3, sim.params.plate.b_m * 1e3
    x, y = np.array([0.0, a, 300.0, 300.0]), np.array([200.0, 200.0, 0.0, b])
    h = sim.frf_um_per_v(x, y, np.array([94.0, 300.0]))
    assert np.all(np.isfinite(h)) and np.abs(h).min() > 0
    ss = build_twin(replace(sim.params, edges="ssss"))
    assert np.abs(ss.frf_um_per_v(x, y, np.array([94.0, 300.0]))).max() < 1e-9


def test_point_on_a_nodal_line_does_not_see_antisymmetric_modes(sim):
    """x = a/2 is a nodal line of every mode antisymmetric in x (uniform seals)."""
    a_mm = sim.params.plate.a_m * 1e3
    phi = sim.modes.shapes(np.array([a_mm / 2e3]), np.array([0.2]))[0]
    anti = (
        sim.modes.shapes(np.array([0.1]), np.array([0.2]))[0]
        + sim.modes.shapes(np.array([sim.params.plate.a_m - 0.1]), np.array([0.2]))[0]
    )
    antisym = np.abs(anti) < 1e-8 * np.abs(phi).max()  # phi(x) = -phi(a - x)
    assert antisym.sum() >= 10
    assert np.abs(phi[antisym]).max() < 1e-9 * np.abs(phi).max()
    # so the FRF at the nodal point is flat at the second mode (antisymmetric (2,1))
    f2 = sim.freq_hz[1]
    assert antisym[1]
    h_node = np.abs(sim.frf_um_per_v([a_mm / 2], [200.0], [f2], ("PA",))).item()
    h_off = np.abs(sim.frf_um_per_v([a_mm / 4], [200.0], [f2], ("PA",))).item()
    assert h_node < 0.1 * h_off


def test_dc_bin_of_a_free_plate_is_infinite_without_warnings_and_masking_works():
    free = build_twin(replace(default_params(), edges="ffff", static_residual=False))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        h = free.frf_um_per_v([100.0], [100.0], np.array([0.0, 0.5, 50.0]))
    assert not np.isfinite(h[0, 0, 0])
    mag = np.abs(h[0, 0])
    mag[np.array([0.0, 0.5, 50.0]) < 5.0] = np.nan  # the cut-off mask
    assert np.nanargmax(mag) == 2


def test_grid_peak_factor_predicts_the_loss_of_a_coarse_grid():
    zeta, f_n = 0.01, 200.0
    g = lambda f: np.abs(frf.modal_receptance(np.array([2 * math.pi * f_n]), f, zeta))[0]  # noqa: E731
    for df in (0.5, 2.0, 5.0):
        grid = np.arange(0.0, 400.0, df) + 0.37 * df  # resonance between bins
        kept = g(grid).max() / g(np.array([f_n]))[0]
        assert frf.grid_peak_factor(grid, f_n, zeta)[0] == pytest.approx(kept, rel=0.02)


def test_coarse_grid_reports_the_peaks_it_misses(sim):
    """0.1 Hz bins are fine at 1 % damping but miss peaks at 0.1 % (bandwidth 2 zeta f)."""
    grid = np.arange(0.0, 625.0 + 1e-9, 0.1)
    assert frf.missed_peaks(grid, sim.freq_hz, 0.01) == []
    missed = frf.missed_peaks(grid, sim.freq_hz, 0.001)
    assert missed, "0.1 Hz is coarser than the 0.1 % half-power bandwidth of low modes"
    assert all(m["peak_kept"] < 0.97 for m in missed)
    coarse = frf.missed_peaks(np.arange(0.0, 626.0, 5.0), sim.freq_hz, 0.01)
    assert len(coarse) >= len(sim.freq_hz[sim.freq_hz < 625]) // 2


def test_many_points_path_equals_the_mode_shape_path(sim):
    """Few (excitation, frequency) pairs are summed in coefficient space: same result."""
    rng = np.random.default_rng(7)
    x, y = rng.uniform(0, 743.46, 500), rng.uniform(0, 447.29, 500)
    few = sim.frf_um_per_v(x, y, np.array([94.4, 465.0]), ("PA", "PALL"))  # 4 < modes
    many = sim.frf_um_per_v(x, y, np.linspace(94.4, 465.0, 60))[[0, 4]][:, :, [0, -1]]
    np.testing.assert_allclose(few, many, rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="outside"):
        sim.frf_um_per_v([800.0], [10.0], [100.0])
