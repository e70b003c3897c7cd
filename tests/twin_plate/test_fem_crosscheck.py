"""Independent finite-element check of the Ritz solver (scikit-fem)."""

from __future__ import annotations

import numpy as np
import pytest

from plugins.twin.plate import ritz

skfem = pytest.importorskip("skfem")


def fem_modes(a, b, nx, ny, d, nu, rhoh, *, kt=0.0, kr=0.0, element="argyris", clamped=False):
    from scipy.sparse.linalg import eigsh
    from skfem.helpers import dd, ddot, dot, grad, trace

    mesh = skfem.MeshTri.init_tensor(np.linspace(0, a, nx + 1), np.linspace(0, b, ny + 1))
    if element == "argyris":
        elem, order = skfem.ElementTriArgyris(), 10
    else:
        elem, order = skfem.ElementTriMorley(), 4
    basis = skfem.Basis(mesh, elem, intorder=order)

    @skfem.BilinearForm
    def bending(u, v, w):
        uu, vv = dd(u), dd(v)
        return d * ((1 - nu) * ddot(uu, vv) + nu * trace(uu) * trace(vv))

    @skfem.BilinearForm
    def mass(u, v, w):
        return rhoh * u * v

    k, m = skfem.asm(bending, basis), skfem.asm(mass, basis)
    if kt or kr:

        @skfem.BilinearForm
        def springs(u, v, w):
            return kt * u * v + kr * dot(grad(u), w.n) * dot(grad(v), w.n)

        k = k + skfem.asm(springs, skfem.FacetBasis(mesh, elem, intorder=order))
    free = np.arange(basis.N)
    if clamped:  # Morley: vertex values + edge normal slopes on the boundary
        free = basis.complement_dofs(basis.get_dofs().all())
    k, m = k[free][:, free], m[free][:, free]
    w2, vecs = eigsh(k, k=10, M=m, sigma=0.0, which="LM")
    order_ = np.argsort(w2)
    full = np.zeros((basis.N, 10))
    full[free] = vecs[:, order_]
    return np.sqrt(np.abs(w2[order_])), basis, full


def test_elastic_seal_plate_matches_argyris_fem():
    """Springs on all edges (the twin's seal model): frequencies and shapes agree."""
    a, b, nu, kt, kr = 1.5, 1.0, 0.22, 1e3, 5.0
    plate = ritz.Plate(a, b, 1.0, 12 * (1 - nu**2), nu, 1.0)  # D = 1, rho h = 1
    modes = ritz.solve_modes(plate, (kt, kr), 20)
    w_fem, basis, vecs = fem_modes(a, b, 9, 6, 1.0, nu, 1.0, kt=kt, kr=kr)
    np.testing.assert_allclose(modes.omega_rad_s[:10], w_fem, rtol=1e-5)
    # mode shapes at probe points: MAC ~ 1 for each (distinct) mode
    rng = np.random.default_rng(0)
    pts = np.vstack([rng.uniform(0, a, 200), rng.uniform(0, b, 200)])
    fem_w = basis.probes(pts) @ vecs
    ritz_w = modes.shapes(pts[0], pts[1])[:, :10]
    mac = (np.sum(fem_w * ritz_w, 0) ** 2) / (np.sum(fem_w**2, 0) * np.sum(ritz_w**2, 0))
    assert mac.min() > 0.9999, mac


def test_clamped_plate_matches_morley_fem_extrapolated():
    """CCCC a/b = 1.5: Morley is O(h^2); Richardson on two meshes gives ~1e-4."""
    a, b = 1.5, 1.0
    w48, _, _ = fem_modes(a, b, 48, 32, 1.0, 0.3, 1.0, element="morley", clamped=True)
    w96, _, _ = fem_modes(a, b, 96, 64, 1.0, 0.3, 1.0, element="morley", clamped=True)
    lam_fem = (4 * w96 - w48) / 3 * a**2
    modes = ritz.solve_modes(ritz.Plate(a, b, 1.0, 12 * 0.91, 0.3, 1.0), "cccc", 20)
    np.testing.assert_allclose(modes.lam[:6], lam_fem[:6], rtol=1e-3)
