"""Plate modes: FACTS reference table, spring limits, closed forms, mode shapes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from plugins.twin.plate import ritz
from plugins.twin.plate.reference import LAMBDA_TABLE, TOLERANCE, ssss_exact

ROWS = list(LAMBDA_TABLE.items())
IDS = [f"{e}-{a:.3f}-nu{nu}" for (e, a, nu), _ in ROWS]


def elastic_lams(modes: ritz.Modes, count: int = 6) -> np.ndarray:
    return modes.lam[modes.n_rigid : modes.n_rigid + count]


@pytest.mark.parametrize(("case", "ref"), ROWS, ids=IDS)
def test_reference_table_exact_limits(case, ref):
    edges, aspect, nu = case
    modes = ritz.solve_modes(ritz.nondim_plate(aspect, nu), edges, 20)
    assert modes.n_rigid == (3 if edges == "ffff" else 0)
    err = np.abs(elastic_lams(modes) / np.array(ref) - 1)
    assert err.max() < TOLERANCE[edges], err


# finite springs large enough to reach the limits: K_t = k_t a^3 / D, K_r = k_r a / D
SPRING_LIMITS = {"ssss": (1e10, 0.0), "cccc": (1e10, 1e6), "ffff": (0.0, 0.0)}


@pytest.mark.parametrize(("case", "ref"), ROWS, ids=IDS)
def test_reference_table_through_spring_limits(case, ref):
    edges, aspect, nu = case
    modes = ritz.solve_modes(ritz.nondim_plate(aspect, nu), SPRING_LIMITS[edges], 20)
    err = np.abs(elastic_lams(modes) / np.array(ref) - 1)
    assert err.max() < TOLERANCE[edges], err


def test_springs_converge_monotonically_to_clamped():
    plate = ritz.nondim_plate(1.5)
    exact = ritz.solve_modes(plate, "cccc", 18).lam[:6]
    errs = [
        np.abs(ritz.solve_modes(plate, (kt, kr), 18).lam[:6] / exact - 1).max()
        for kt, kr in ((1e4, 1e2), (1e6, 1e4), (1e8, 1e6))
    ]
    assert errs[0] > errs[1] > errs[2]
    assert errs[2] < 1e-4
    # springs only stiffen: every finite-spring frequency is below the clamped one
    soft = ritz.solve_modes(plate, (1e6, 1e4), 18).lam[:6]
    assert np.all(soft < exact)


def test_ssss_matches_closed_form_for_twenty_modes():
    aspect = 743.46 / 447.29
    modes = ritz.solve_modes(ritz.nondim_plate(aspect, 0.22), "ssss", 22)
    np.testing.assert_allclose(modes.lam[:20], ssss_exact(aspect, 20), rtol=1e-7)


def test_free_plate_has_three_rigid_modes():
    modes = ritz.solve_modes(ritz.nondim_plate(1.5), "ffff", 16)
    assert modes.n_rigid == 3
    assert np.all(modes.omega_rad_s[:3] == 0) and modes.lam[3] > 10


def test_ssss_mode_shapes_match_sines():
    a, b = 1.0, 1 / 1.5
    modes = ritz.solve_modes(ritz.nondim_plate(1.5), "ssss", 20)
    x, y = np.meshgrid(np.linspace(0, a, 31), np.linspace(0, b, 23))
    phi = modes.shapes(x.ravel(), y.ravel())
    # a/b = 1.5: modes 1-4 are (m, n) = (1, 1), (2, 1), (1, 2), (3, 1), all distinct
    for r, (m, n) in enumerate(((1, 1), (2, 1), (1, 2), (3, 1))):
        s = np.sin(m * math.pi * x.ravel() / a) * np.sin(n * math.pi * y.ravel() / b)
        mac = (phi[:, r] @ s) ** 2 / ((phi[:, r] @ phi[:, r]) * (s @ s))
        assert mac > 0.99999
        # mass normalised: integral rho h phi^2 = 1 -> amplitude 2 / sqrt(a b)
        amp = (phi[:, r] @ s) / (s @ s)
        assert abs(amp) == pytest.approx(2 / math.sqrt(a * b), rel=1e-6)


def test_laplacian_matches_analytic_on_ssss():
    a, b = 1.0, 1 / 1.5
    modes = ritz.solve_modes(ritz.nondim_plate(1.5), "ssss", 20)
    x = np.array([0.13, 0.5, 0.77, 0.0, 1.0])
    y = np.array([0.2, 0.41, 0.05, 0.3, 0.66])
    w = modes.shapes(x, y)[:, 0]
    lap = modes.shapes(x, y, "lap")[:, 0]
    k2 = (math.pi / a) ** 2 + (math.pi / b) ** 2
    np.testing.assert_allclose(lap, -k2 * w, atol=1e-6 * k2 * np.abs(w).max())


def test_derivatives_match_finite_differences():
    modes = ritz.solve_modes(ritz.nondim_plate(1.662, 0.22), (2e3, 3.0), 18)
    x0, y0, eps = np.array([0.31]), np.array([0.27]), 1e-4
    w = lambda dx, dy: modes.shapes(x0 + dx, y0 + dy)  # noqa: E731
    fd_xx = (w(eps, 0) - 2 * w(0, 0) + w(-eps, 0)) / eps**2
    fd_xy = (w(eps, eps) - w(eps, -eps) - w(-eps, eps) + w(-eps, -eps)) / (4 * eps**2)
    scale = np.abs(modes.shapes(x0, y0, "w_xx")).max()
    np.testing.assert_allclose(modes.shapes(x0, y0, "w_xx"), fd_xx, atol=1e-4 * scale)
    np.testing.assert_allclose(modes.shapes(x0, y0, "w_xy"), fd_xy, atol=1e-4 * scale)


def test_repeated_clamped_square_modes_span_the_rotated_shape():
    """CCCC square modes 2 and 3 are degenerate: compare them as a subspace."""
    modes = ritz.solve_modes(ritz.nondim_plate(1.0), "cccc", 18)
    assert modes.lam[1] == pytest.approx(modes.lam[2], rel=1e-9)
    g = np.linspace(0, 1, 25)
    x, y = (v.ravel() for v in np.meshgrid(g, g))
    pair = modes.shapes(x, y)[:, 1:3]
    rotated = modes.shapes(y, 1 - x)[:, 1:3]  # the same pair rotated by 90 degrees
    q, _ = np.linalg.qr(pair)
    resid = rotated - q @ (q.T @ rotated)
    assert np.linalg.norm(resid) < 1e-8 * np.linalg.norm(rotated)


def test_points_on_the_edge_and_nodal_line():
    modes = ritz.solve_modes(ritz.nondim_plate(1.5), "ssss", 18)
    b = 1 / 1.5
    edge = modes.shapes(np.array([0.0, 1.0, 0.4, 0.6]), np.array([0.3, 0.2, 0.0, b]))
    assert np.abs(edge).max() < 1e-9  # simply supported edges do not move
    # mode 2 = (2, 1): nodal line at x = a / 2
    mid = modes.shapes(np.full(5, 0.5), np.linspace(0.05, 0.6, 5))[:, 1]
    assert np.abs(mid).max() < 1e-9
    with pytest.raises(ValueError, match="outside"):
        modes.shapes(np.array([1.01]), np.array([0.1]))


def test_cache_hits_on_equal_inputs_only():
    plate = ritz.nondim_plate(1.3)
    m1 = ritz.solve_modes(plate, "sscc", 12)
    assert ritz.solve_modes(plate, "sscc", 12) is m1
    assert ritz.solve_modes(plate, "sscf", 12) is not m1
    assert ritz.solve_modes(ritz.nondim_plate(1.3001), "sscc", 12) is not m1


def test_bad_edge_specs_are_rejected():
    with pytest.raises(ValueError, match="f/s/c"):
        ritz.edge_springs("ssx")
    with pytest.raises(ValueError, match=">= 0"):
        ritz.edge_springs((-1.0, 0.0))
