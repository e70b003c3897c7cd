"""Kirchhoff rectangular plate modes by Rayleigh-Ritz in an orthonormal Legendre basis.

Coordinates: x in [0, a] (long side), y in [0, b]; the basis lives on xi, eta in [-1, 1]
with x = a (xi + 1) / 2, y = b (eta + 1) / 2. The trial functions are tensor products of
L2-orthonormal Legendre polynomials p_n = sqrt((2n+1)/2) P_n, so the mass matrix is the
identity times rho h a b / 4 and stays perfectly conditioned.

Edges carry elastic supports as boundary energy 1/2 * closed-integral(k_t w^2 + k_r w_n^2)
ds (k_t in N/m^2, k_r in N/rad: per unit length). The infinite-spring limits are exact:
``k = inf`` removes the constrained direction from the basis (w = 0 for k_t, w_n = 0 for
k_r) through the null space of the edge-value rows, which keeps the basis orthonormal.

Edge names: ``x0`` (x = 0), ``x1`` (x = a), ``y0`` (y = 0), ``y1`` (y = b).
"""

from __future__ import annotations

import hashlib
import math
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np
from numpy.polynomial import legendre as leg
from scipy import linalg

EDGES: tuple[str, ...] = ("x0", "x1", "y0", "y1")
INF = math.inf

#: Named edge conditions as (k_t, k_r) spring limits.
FREE = (0.0, 0.0)
SIMPLY_SUPPORTED = (INF, 0.0)
CLAMPED = (INF, INF)
_NAMED = {"f": FREE, "s": SIMPLY_SUPPORTED, "c": CLAMPED}


@dataclass(frozen=True)
class Plate:
    """Geometry and material of a rectangular Kirchhoff plate (SI units)."""

    a_m: float  # long side, along x
    b_m: float  # short side, along y
    h_m: float
    youngs_pa: float
    poisson: float
    density_kg_m3: float

    @property
    def flexural_rigidity(self) -> float:
        """D = E h^3 / (12 (1 - nu^2)) in N m."""
        return self.youngs_pa * self.h_m**3 / (12.0 * (1.0 - self.poisson**2))

    @property
    def mass_per_area(self) -> float:
        return self.density_kg_m3 * self.h_m

    def lam(self, omega_rad_s: np.ndarray) -> np.ndarray:
        """Frequency parameter lambda = omega a^2 sqrt(rho h / D)."""
        return omega_rad_s * self.a_m**2 * math.sqrt(self.mass_per_area / self.flexural_rigidity)

    def omega(self, lam: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`lam`."""
        return lam / (self.a_m**2 * math.sqrt(self.mass_per_area / self.flexural_rigidity))


Springs = tuple[float, float]  # (k_t N/m^2, k_r N/rad)


def edge_springs(spec: str | Springs | dict[str, Springs]) -> dict[str, Springs]:
    """Normalise an edge specification to ``{edge: (k_t, k_r)}``.

    ``spec`` is a 4-letter string of f/s/c in the order x0 x1 y0 y1 (e.g. ``"ssss"``),
    one ``(k_t, k_r)`` pair for all edges, or per edge a dict (or tuple of pairs).
    """
    if isinstance(spec, str):
        s = spec.lower()
        if len(s) != 4 or any(c not in _NAMED for c in s):
            raise ValueError(f"edge string {spec!r}: use 4 letters of f/s/c (x0 x1 y0 y1)")
        return {e: _NAMED[c] for e, c in zip(EDGES, s, strict=True)}
    if isinstance(spec, tuple) and spec and isinstance(spec[0], tuple):
        spec = dict(spec)  # ((edge, (k_t, k_r)), ...): the hashable per-edge form
    if isinstance(spec, dict):
        missing = [e for e in EDGES if e not in spec]
        if missing:
            raise ValueError(f"edge springs: missing edges {missing}")
        out = {e: (float(spec[e][0]), float(spec[e][1])) for e in EDGES}
    else:
        kt, kr = spec
        out = {e: (float(kt), float(kr)) for e in EDGES}
    for e, (kt, kr) in out.items():
        if not (kt >= 0 and kr >= 0):
            raise ValueError(f"edge {e}: springs must be >= 0, got {(kt, kr)}")
    return out


# ------------------------------------------------------------------ 1D Legendre basis
def _legendre_coeffs(n: int) -> np.ndarray:
    """(n, n) Legendre-series coefficients of the orthonormal p_0..p_{n-1} (columns)."""
    return np.diag(np.sqrt((2.0 * np.arange(n) + 1.0) / 2.0))


def basis_1d(xi: np.ndarray, n: int, deriv: int = 0) -> np.ndarray:
    """Values of d^deriv p_k / dxi^deriv at ``xi``: shape (len(xi), n).

    ``deriv = -1`` gives the antiderivative that vanishes at xi = -1.
    """
    c = _legendre_coeffs(n)
    if deriv > 0:
        c = leg.legder(c, deriv, axis=0)
    elif deriv < 0:
        c = leg.legint(c, -deriv, lbnd=-1.0, axis=0)
    return leg.legvander(np.asarray(xi, dtype=float), c.shape[0] - 1) @ c


def constrained_transform(n: int, lo: Springs, hi: Springs) -> np.ndarray:
    """Orthonormal (n, n_free) map to the sub-basis meeting the infinite-spring limits.

    ``lo``/``hi`` are the (k_t, k_r) of the edges at xi = -1 / +1: an infinite k_t
    imposes w = 0 there, an infinite k_r imposes dw/dxi = 0.
    """
    rows = []
    ends = np.array([-1.0, 1.0])
    v0, v1 = basis_1d(ends, n, 0), basis_1d(ends, n, 1)
    for i, (kt, kr) in enumerate((lo, hi)):
        if math.isinf(kt):
            rows.append(v0[i])
        if math.isinf(kr):
            rows.append(v1[i])
    if not rows:
        return np.eye(n)
    return linalg.null_space(np.array(rows))


@dataclass(frozen=True)
class Basis1D:
    """The (possibly constrained) 1D basis q = p @ T and its Gram-type matrices."""

    n: int
    t: np.ndarray  # (n, m)
    e11: np.ndarray  # int q' q'^T
    e22: np.ndarray  # int q'' q''^T
    e20: np.ndarray  # int q'' q^T  (row: q'', column: q)
    ends0: np.ndarray  # (2, m) q at -1, +1
    ends1: np.ndarray  # (2, m) q' at -1, +1

    def values(self, xi: np.ndarray, deriv: int = 0) -> np.ndarray:
        return basis_1d(xi, self.n, deriv) @ self.t


def make_basis_1d(n: int, lo: Springs, hi: Springs) -> Basis1D:
    t = constrained_transform(n, lo, hi)
    xg, wg = leg.leggauss(n + 2)
    q0 = basis_1d(xg, n, 0) @ t
    q1 = basis_1d(xg, n, 1) @ t
    q2 = basis_1d(xg, n, 2) @ t
    ends = np.array([-1.0, 1.0])
    return Basis1D(
        n=n,
        t=t,
        e11=(q1 * wg[:, None]).T @ q1,
        e22=(q2 * wg[:, None]).T @ q2,
        e20=(q2 * wg[:, None]).T @ q0,
        ends0=basis_1d(ends, n, 0) @ t,
        ends1=basis_1d(ends, n, 1) @ t,
    )


# ------------------------------------------------------------------ 2D plate matrices
@dataclass(frozen=True)
class RitzSystem:
    plate: Plate
    springs: dict[str, Springs]
    bx: Basis1D
    by: Basis1D
    k: np.ndarray  # stiffness (nx*ny square), coefficient index i*ny + j
    m_scale: float  # M = m_scale * I


def assemble(plate: Plate, springs: dict[str, Springs], n: int) -> RitzSystem:
    """Stiffness matrix of the plate (bending + finite edge springs) in the Ritz basis."""
    a, b, nu, d = plate.a_m, plate.b_m, plate.poisson, plate.flexural_rigidity
    bx = make_basis_1d(n, springs["x0"], springs["x1"])
    by = make_basis_1d(n, springs["y0"], springs["y1"])
    ix, iy = np.eye(bx.t.shape[1]), np.eye(by.t.shape[1])
    sx, sy = 2.0 / a, 2.0 / b
    jac = a * b / 4.0
    cross = np.kron(bx.e20, by.e20.T)
    k = (
        d
        * jac
        * (
            sx**4 * np.kron(bx.e22, iy)
            + sy**4 * np.kron(ix, by.e22)
            + nu * sx**2 * sy**2 * (cross + cross.T)
            + 2.0 * (1.0 - nu) * sx**2 * sy**2 * np.kron(bx.e11, by.e11)
        )
    )
    # finite edge springs: edges x0/x1 run along y (length element b/2 d eta), etc.
    for end, edge in enumerate(("x0", "x1")):
        kt, kr = springs[edge]
        blk = np.zeros((ix.shape[0], ix.shape[0]))
        if 0 < kt < INF:
            blk += kt * np.outer(bx.ends0[end], bx.ends0[end])
        if 0 < kr < INF:
            blk += kr * sx**2 * np.outer(bx.ends1[end], bx.ends1[end])
        if blk.any():
            k += (b / 2.0) * np.kron(blk, iy)
    for end, edge in enumerate(("y0", "y1")):
        kt, kr = springs[edge]
        blk = np.zeros((iy.shape[0], iy.shape[0]))
        if 0 < kt < INF:
            blk += kt * np.outer(by.ends0[end], by.ends0[end])
        if 0 < kr < INF:
            blk += kr * sy**2 * np.outer(by.ends1[end], by.ends1[end])
        if blk.any():
            k += (a / 2.0) * np.kron(ix, blk)
    k = 0.5 * (k + k.T)
    return RitzSystem(plate, springs, bx, by, k, plate.mass_per_area * jac)


@dataclass(frozen=True)
class Modes:
    """Mass-normalised modes: phi_r = sum_ij coeffs[r, i, j] q_i(xi) q_j(eta)."""

    system: RitzSystem
    omega_rad_s: np.ndarray  # (R,) ascending, >= 0
    coeffs: np.ndarray  # (R, mx, my), mass-normalised (phi^T M phi = 1, in 1/sqrt(kg))
    n_rigid: int = 0
    key: str = field(default="", compare=False)

    @property
    def plate(self) -> Plate:
        return self.system.plate

    @property
    def freq_hz(self) -> np.ndarray:
        return self.omega_rad_s / (2.0 * math.pi)

    @property
    def lam(self) -> np.ndarray:
        return self.plate.lam(self.omega_rad_s)

    def elastic(self) -> slice:
        """Slice of the elastic (non rigid-body) modes."""
        return slice(self.n_rigid, None)

    def shapes(self, x_m: np.ndarray, y_m: np.ndarray, what: str = "w") -> np.ndarray:
        """Mode shapes at points: (P, R). ``what``: w, w_x, w_y, w_xx, w_yy, w_xy, lap."""
        return evaluate(self, x_m, y_m, what)


def _xi(x_m: np.ndarray, length_m: float) -> np.ndarray:
    return 2.0 * np.asarray(x_m, dtype=float) / length_m - 1.0


def evaluate(modes: Modes, x_m: np.ndarray, y_m: np.ndarray, what: str = "w") -> np.ndarray:
    """Mode-shape quantity ``what`` at points (x_m[p], y_m[p]): array (P, R)."""
    x_m, y_m = np.broadcast_arrays(np.atleast_1d(x_m), np.atleast_1d(y_m))
    a, b = modes.plate.a_m, modes.plate.b_m
    xi, eta = _xi(x_m.ravel(), a), _xi(y_m.ravel(), b)
    if np.any(np.abs(xi) > 1 + 1e-9) or np.any(np.abs(eta) > 1 + 1e-9):
        raise ValueError("point outside the plate")
    sx, sy = 2.0 / a, 2.0 / b
    orders = {
        "w": [(0, 0, 1.0)],
        "w_x": [(1, 0, sx)],
        "w_y": [(0, 1, sy)],
        "w_xx": [(2, 0, sx**2)],
        "w_yy": [(0, 2, sy**2)],
        "w_xy": [(1, 1, sx * sy)],
        "lap": [(2, 0, sx**2), (0, 2, sy**2)],
    }
    if what not in orders:
        raise ValueError(f"unknown quantity {what!r}: use one of {', '.join(orders)}")
    out = 0.0
    for dx, dy, scale in orders[what]:
        vx = modes.system.bx.values(xi, dx)  # (P, mx)
        vy = modes.system.by.values(eta, dy)  # (P, my)
        tmp = vx @ modes.coeffs  # (R, P, my): one BLAS call per mode
        out = out + scale * np.einsum("rpj,pj->pr", tmp, vy)
    return out


# ------------------------------------------------------------------ solve + cache
_CACHE: OrderedDict[str, Modes] = OrderedDict()
_CACHE_SIZE = 16


def modes_key(plate: Plate, springs: dict[str, Springs], n: int, f_max_hz: float | None) -> str:
    """Hash of every input of :func:`solve_modes` (the cache key)."""
    parts = [repr(tuple(float(v) for v in vars(plate).values())), str(n), repr(f_max_hz)]
    parts += [f"{e}:{springs[e][0]!r}:{springs[e][1]!r}" for e in EDGES]
    return hashlib.sha1("|".join(parts).encode()).hexdigest()


def cache_clear() -> None:
    _CACHE.clear()


def solve_modes(
    plate: Plate,
    edges: str | Springs | dict[str, Springs],
    n: int = 20,
    f_max_hz: float | None = None,
    rigid_lam: float = 1e-2,
) -> Modes:
    """Natural modes, ascending; only those up to ``f_max_hz`` when given (cached).

    Rigid-body modes (lambda < ``rigid_lam``, only possible with free edges) are kept at
    the front with omega = 0 and counted in ``n_rigid``.
    """
    springs = edge_springs(edges)
    key = modes_key(plate, springs, n, f_max_hz)
    hit = _CACHE.get(key)
    if hit is not None:
        _CACHE.move_to_end(key)
        return hit
    system = assemble(plate, springs, n)
    kw = {}
    if f_max_hz is not None:
        w2_max = (2.0 * math.pi * f_max_hz) ** 2 * system.m_scale
        kw = {"subset_by_value": (-np.inf, w2_max)}
    evals, evecs = linalg.eigh(system.k, driver="evr" if kw else "evd", **kw)
    omega2 = evals / system.m_scale
    omega = np.sqrt(np.clip(omega2, 0.0, None))
    lam = plate.lam(omega)
    n_rigid = int(np.sum(lam < rigid_lam))
    omega[:n_rigid] = 0.0
    coeffs = evecs.T / math.sqrt(system.m_scale)
    mx, my = system.bx.t.shape[1], system.by.t.shape[1]
    modes = Modes(system, omega, coeffs.reshape(-1, mx, my), n_rigid, key)
    _CACHE[key] = modes
    if len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    return modes


def nondim_plate(aspect: float, poisson: float = 0.3) -> Plate:
    """Plate with a = 1, D = 1, rho h = 1, b = a / aspect: omega equals lambda."""
    h = 1.0
    e = 12.0 * (1.0 - poisson**2)
    return Plate(1.0, 1.0 / aspect, h, e, poisson, 1.0)
