"""Independent patches: the per-pair solver against analytic two-patch cases, the
scipy generalised eigensolver and brute force over phases; its hard cases (no passive
response, parallel FRFs, rank-deficient and non-finite maps)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from console.core.errors import UserError
from plugins.vibrotactile.independent import (
    focus_weights,
    generalized_max,
    generalized_max_batched,
    max_min_weights,
    pair_weights,
    paper_pair_drives,
    patch_frf,
    scale_to_peak,
    solve_pairs,
    square_levels_of,
)
from plugins.vibrotactile.thresholds import Perception


def objective(h_a, h_b, x, eps):
    return abs(h_a @ x) ** 2 / (abs(h_b @ x) ** 2 + eps * np.sum(np.abs(x) ** 2))


def test_two_patches_analytic():
    # h_a = (1, 0), h_b = (1, 1): x = (1 + eps, -1) nulls b up to eps, and the best ratio
    # is (1 + eps) / (eps (2 + eps)) (rank-one A: h_a^T B^-1 conj(h_a) by hand)
    eps = 1e-3
    h_a, h_b = np.array([1.0, 0.0]), np.array([1.0, 1.0])
    x, lam = focus_weights(h_a, h_b, eps)
    assert lam == pytest.approx((1 + eps) / (eps * (2 + eps)), rel=1e-12)
    assert x[0] / x[1] == pytest.approx(-(1 + eps), rel=1e-12)
    assert objective(h_a, h_b, x, eps) == pytest.approx(lam, rel=1e-12)
    # symmetric case: h_a = (1, 1), h_b = (1, -1): drive both in phase, ratio 2 / eps
    x, lam = focus_weights(np.array([1.0, 1.0]), np.array([1.0, -1.0]), eps)
    assert lam == pytest.approx(2 / eps, rel=1e-12)
    assert x[0] == pytest.approx(x[1])


def test_closed_form_is_the_generalised_eigenvector():
    rng = np.random.default_rng(3)
    for _ in range(20):
        h_a, h_b = rng.standard_normal((2, 4)) + 1j * rng.standard_normal((2, 4))
        eps = 10 ** rng.uniform(-4, 0)
        a = np.outer(np.conj(h_a), h_a)
        b = np.outer(np.conj(h_b), h_b) + eps * np.eye(4)
        v, w = generalized_max(a, b)
        x, lam = focus_weights(h_a, h_b, eps)
        assert lam == pytest.approx(w, rel=1e-8)
        # the same direction up to a complex factor
        assert abs(np.vdot(v, x)) / (np.linalg.norm(v) * np.linalg.norm(x)) == pytest.approx(1.0)
        vb, wb = generalized_max_batched(a[None], b[None])
        assert wb[0] == pytest.approx(w, rel=1e-8)
        assert objective(h_a, h_b, vb[0], eps) == pytest.approx(w, rel=1e-8)


def test_brute_force_over_phases_and_amplitudes():
    """Two patches, every drive (1, t e^{i phi}) or (t e^{i phi}, 1) on a fine grid: none
    beats the closed form, and the best is within 1 % of it (the grid step)."""
    rng = np.random.default_rng(7)
    t = np.linspace(0, 1, 401)
    phi = np.linspace(0, 2 * np.pi, 721)
    z = (t[:, None] * np.exp(1j * phi[None])).ravel()
    for _ in range(5):
        h_a, h_b = rng.standard_normal((2, 2)) + 1j * rng.standard_normal((2, 2))
        eps = 0.01
        _, lam = focus_weights(h_a, h_b, eps)
        best = 0.0
        for xs in (np.stack([np.ones_like(z), z], 1), np.stack([z, np.ones_like(z)], 1)):
            r = np.abs(xs @ h_a) ** 2 / (np.abs(xs @ h_b) ** 2 + eps * np.sum(np.abs(xs) ** 2, 1))
            best = max(best, float(r.max()))
        assert best <= lam * (1 + 1e-9)
        assert best == pytest.approx(lam, rel=1e-2)


def test_no_passive_response_is_time_reversal():
    h_a = np.array([0.3 + 0.1j, -0.2j, 0.05, 0.4 - 0.3j])
    x = pair_weights(h_a, np.zeros(4, complex), 1e-6, "independent")
    tr = pair_weights(h_a, np.zeros(4, complex), 1e-6, "time_reversal")
    np.testing.assert_allclose(x, tr, rtol=1e-12)
    np.testing.assert_allclose(x, np.conj(h_a) / np.abs(h_a).max(), rtol=1e-12)


def test_parallel_frfs_give_their_ratio_only():
    """h_a = c h_b: no drive separates them; the contrast is |c| whatever the weights."""
    h_b = np.array([0.3 + 0.1j, -0.2j, 0.05, 0.4 - 0.3j])
    c = 0.5 * np.exp(0.7j)
    x = pair_weights(c * h_b, h_b, 1e-9, "independent")
    assert abs(c * h_b @ x) / abs(h_b @ x) == pytest.approx(abs(c), rel=1e-9)


def test_scale_to_peak_and_phase():
    rng = np.random.default_rng(0)
    x = rng.standard_normal((5, 4)) + 1j * rng.standard_normal((5, 4))
    h = rng.standard_normal((5, 4)) + 1j * rng.standard_normal((5, 4))
    y = scale_to_peak(x, h)
    np.testing.assert_allclose(np.abs(y).max(axis=1), 1.0)
    r = np.sum(h * y, axis=1)
    assert np.all(r.real > 0) and np.allclose(r.imag, 0, atol=1e-12)


# ------------------------------------------------------------------ on maps
@pytest.fixture(scope="module")
def perception():
    return Perception()


def test_independent_beats_the_tables_on_the_analytic_plate(ss_map, ss_tables, perception):
    """On the simply supported plate's exact map the per-patch focus gives at least 6 dB
    more map contrast than the paper's tables for most pairs (same peak volts)."""
    rng = np.random.default_rng(0)
    n = ss_map.points.size
    pairs = [tuple(map(int, rng.choice(n, 2, replace=False))) for _ in range(60)]
    ind = solve_pairs(ss_map, pairs, perception, cap_v=95.0, band_hz=ss_tables.band_hz)
    pap = paper_pair_drives(ss_tables, pairs, perception, cap_v=95.0)
    gain = [a["contrast_db"] - p["contrast_db"] for a, p in zip(ind, pap, strict=True) if p]
    assert np.median(gain) >= 6.0
    for a in ind:
        assert np.abs(a["weights"]).max() == pytest.approx(1.0)
        assert a["amplitude_v"] <= 95.0
        assert a["expected_contrast_db"] <= a["contrast_db"] + 1e-9


def test_rank_deficient_map(ss_map, perception):
    """PC an exact copy of PA (a symmetric table): the solver still returns finite,
    peak-scaled drives, and the reference eigensolver copes with a singular A."""
    frf = ss_map.frf_um_per_v.copy()
    i = {e: k for k, e in enumerate(ss_map.excitations)}
    frf[i["PC"]] = frf[i["PA"]]
    m = replace(ss_map, frf_um_per_v=frf)
    ans = solve_pairs(m, [(3, 40), (40, 3), (10, 11)], perception, cap_v=95.0)
    for a in ans:
        assert np.all(np.isfinite(a["weights"])) and np.isfinite(a["contrast_db"])
        assert np.abs(a["weights"]).max() == pytest.approx(1.0)
    h = patch_frf(m)[:, 3, 100]
    v, w = generalized_max(np.outer(np.conj(h), h), 1e-3 * np.eye(4))
    assert np.isfinite(w) and np.all(np.isfinite(v))


def test_non_finite_map_is_one_line(ss_map, perception):
    frf = ss_map.frf_um_per_v.copy()
    frf[ss_map.excitations.index("PB"), 5, 200] = np.nan
    m = replace(ss_map, frf_um_per_v=frf)
    with pytest.raises(UserError) as exc:
        solve_pairs(m, [(0, 1)], perception, cap_v=95.0, band_hz=1e9)
    msg = str(exc.value)
    assert "\n" not in msg and "frf_um_per_v" in msg and "PB" in msg and "point 6" in msg


def test_missing_patch_and_same_point(ss_map, perception):
    keep = [k for k, e in enumerate(ss_map.excitations) if e != "PD"]
    m = replace(
        ss_map,
        frf_um_per_v=ss_map.frf_um_per_v[keep],
        excitations=tuple(ss_map.excitations[k] for k in keep),
    )
    with pytest.raises(UserError, match="PD"):
        solve_pairs(m, [(0, 1)], perception, cap_v=95.0)
    with pytest.raises(UserError, match="same"):
        solve_pairs(ss_map, [(2, 2)], perception, cap_v=95.0)
    with pytest.raises(UserError, match="method"):
        solve_pairs(ss_map, [(0, 1)], perception, cap_v=95.0, method="magic")


def test_max_min_never_worse_than_the_summed_problem():
    """Two squares side by side (2 x 1 lattice of 3 x 3 points each, 4 patches): the
    reweighted drive's weakest-active / strongest-passive contrast is at least the
    plain summed eigenproblem's."""
    rng = np.random.default_rng(5)
    squares, n = 2, 3
    h = rng.standard_normal(((squares * n) ** 2, 4)) + 1j * rng.standard_normal(
        ((squares * n) ** 2, 4)
    )
    side_a = np.array([[True, False], [False, False]])
    side_b = np.array([[False, True], [False, False]])
    x, c = max_min_weights(h, side_a, side_b, squares, n, eps=1e-3)
    lv = square_levels_of(np.abs(h @ x), squares, n)
    assert c == pytest.approx(20 * math.log10(lv[side_a].min() / lv[side_b].max()))
    sq = (np.arange(squares * n)[:, None] // n) * squares + np.arange(squares * n)[None] // n
    sq = sq.ravel()
    a = sum(np.outer(np.conj(r), r) for r in h[sq == 0]) / n**2
    b = sum(np.outer(np.conj(r), r) for r in h[sq == 1]) / n**2 + 1e-3 * np.eye(4)
    v, _ = generalized_max(a, b)
    lv0 = square_levels_of(np.abs(h @ v), squares, n)
    assert c >= 20 * math.log10(lv0[side_a].min() / lv0[side_b].max()) - 1e-9
