"""Independent patches: a complex amplitude per patch and frequency that focuses the
vibration under the active point (or side of a hand) and cancels it under the passive one.

With each patch PA..PD on its own channel, the plate's displacement at a point is
``h^T x`` with ``h`` (4,) the point's FRFs (um/V, the map's PA..PD) and ``x`` (4,) the
complex drive per patch (volts peak, phase). Per pair (active a, passive b) and map bin:

    maximise  |h_a^T x|^2 / (|h_b^T x|^2 + eps ||x||^2)

a generalised Hermitian eigenproblem ``A x = lambda B x`` with ``A = conj(h_a) h_a^T`` and
``B = conj(h_b) h_b^T + eps I``. ``eps = sigma^2`` is the map's error variance per entry
(``map_error_rel`` x the bin's RMS |H| over points and patches): the expected passive
energy when the map is off by sigma, so the solution never relies on a null the map
cannot promise. ``A`` has rank one, so ``x = B^-1 conj(h_a)`` in closed form
(Sherman-Morrison, vectorised over pairs and bins; ``scipy.linalg.eigh`` is the
reference). Under a hand ``A`` and ``B`` are sums over the subgrid points of the active
and passive sides and the max-min variant reweights the squares so the weakest active
square gains against the strongest passive one. Time-reversal focusing (``x = conj(h_a)``)
is the second method (it maximises the active level alone, ignores the passive point).

Every ``x`` is scaled to 1 V peak on its strongest patch: at a drive of V volts no patch
sees more than V, the same peak voltage as the paper's tables (one actuator, or PALL,
at V). The frequency is the bin of best (regularised) contrast among those where the
active level at the drive cap reaches the profile's sensation level (else 3 JND above the
fingertip threshold, else the strongest bin).
"""

from __future__ import annotations

import math
from collections.abc import Iterable

import numpy as np

from console.plugin_api import UserError, VibrationMap
from plugins.vibrotactile.hand import side_masks
from plugins.vibrotactile.interp import interpolate_lattice
from plugins.vibrotactile.tables import usable_bins
from plugins.vibrotactile.thresholds import Perception

PATCHES: tuple[str, ...] = ("PA", "PB", "PC", "PD")
METHODS: tuple[str, ...] = ("independent", "time_reversal")
#: default map error (sigma / bin RMS |H|): -26 dB, the twin vibrometer's scatter is far below
DEFAULT_MAP_ERROR_REL = 0.05


# --------------------------------------------------------------------------- the map
def patch_frf(m: VibrationMap, bins: np.ndarray | None = None) -> np.ndarray:
    """(4, P, K) FRFs of PA..PD at ``bins``; one-line ``UserError`` if a patch is
    missing or a value is not finite."""
    missing = [p for p in PATCHES if p not in m.excitations]
    if missing:
        raise UserError(
            f"vibration map: independent patches need PA PB PC PD, {' '.join(missing)} "
            "missing; measure each patch on its own (haptable frf measure)"
        )
    idx = [m.excitations.index(p) for p in PATCHES]
    h = m.frf_um_per_v[idx] if bins is None else m.frf_um_per_v[idx][:, :, bins]
    if not np.all(np.isfinite(h)):
        e, p, k = np.argwhere(~np.isfinite(h))[0]
        f = m.freq_hz[k if bins is None else bins[k]]
        raise UserError(
            f"vibration map: frf_um_per_v of {PATCHES[e]} at point {int(m.points[p])}, "
            f"{f:g} Hz is not finite; re-measure or re-import the map"
        )
    return h


def error_variance(h: np.ndarray, rel: float) -> np.ndarray:
    """(K,) eps = (rel x RMS |H| over patches and points)^2 per bin (a floor keeps it > 0)."""
    if not rel > 0:
        raise UserError(f"map_error_rel {rel!r}: give a positive fraction (e.g. 0.05)")
    ms = np.mean(np.abs(h) ** 2, axis=tuple(range(h.ndim - 1)))
    floor = 1e-12 * max(float(ms.max(initial=0.0)), 1e-30)
    return rel**2 * np.maximum(ms, floor)


# --------------------------------------------------------------------------- solvers
def focus_weights(
    h_a: np.ndarray, h_b: np.ndarray, eps: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray]:
    """Closed form of the pair problem over leading axes: (x, lambda).

    ``h_a``, ``h_b``: (..., N) complex; ``eps``: broadcast to the leading axes. Returns
    ``x = B^-1 conj(h_a)`` (unscaled) and the largest generalised eigenvalue
    ``lambda = h_a^T B^-1 conj(h_a)`` (the best regularised energy ratio)."""
    g, c = np.conj(h_a), np.conj(h_b)
    eps = np.asarray(eps, float)
    cg = np.sum(np.conj(c) * g, axis=-1)  # c^H g
    cc = np.sum(np.abs(c) ** 2, axis=-1)
    gg = np.sum(np.abs(g) ** 2, axis=-1)
    x = g - c * (cg / (eps + cc))[..., None]
    lam = (gg - np.abs(cg) ** 2 / (eps + cc)) / eps
    return x, lam


def generalized_max(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, float]:
    """Reference: the eigenvector and value of the largest ``A x = lambda B x``
    (``scipy.linalg.eigh``; ``B`` must be positive definite)."""
    from scipy.linalg import eigh

    w, v = eigh(a, b, subset_by_index=[a.shape[0] - 1, a.shape[0] - 1])
    return v[:, 0], float(w[0])


def generalized_max_batched(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``generalized_max`` over leading axes (Cholesky of B, then ``numpy.linalg.eigh``):
    (x (..., N), lambda (...))."""
    ell = np.linalg.cholesky(b)
    li = np.linalg.inv(ell)
    c = li @ a @ np.conj(np.swapaxes(li, -1, -2))
    c = 0.5 * (c + np.conj(np.swapaxes(c, -1, -2)))
    w, v = np.linalg.eigh(c)
    x = np.conj(np.swapaxes(li, -1, -2)) @ v[..., -1:]
    return x[..., 0], w[..., -1]


def scale_to_peak(x: np.ndarray, h_a: np.ndarray | None = None) -> np.ndarray:
    """``x`` scaled to 1 on its largest patch (over the last axis); with ``h_a`` also
    turned so the active response ``h_a^T x`` is real and positive."""
    x = np.asarray(x, complex)
    peak = np.abs(x).max(axis=-1, keepdims=True)
    x = x / np.where(peak > 0, peak, 1.0)
    if h_a is not None:
        r = np.sum(h_a * x, axis=-1, keepdims=True)
        x = x * np.where(np.abs(r) > 0, np.conj(r) / np.maximum(np.abs(r), 1e-300), 1.0)
    return x


def pair_weights(
    h_a: np.ndarray, h_b: np.ndarray, eps: np.ndarray | float, method: str = "independent"
) -> np.ndarray:
    """Peak-scaled drives (..., 4) of ``method`` for the active/passive FRFs (..., 4)."""
    if method == "independent":
        x, _ = focus_weights(h_a, h_b, eps)
    elif method == "time_reversal":
        x = np.conj(h_a)
    else:
        raise UserError(f"method {method!r}: use {', '.join(METHODS)}")
    return scale_to_peak(x, h_a)


# --------------------------------------------------------------------------- pairs
def _required_sl(sl_db: np.ndarray, target_sl_db: float, floor_db: float) -> np.ndarray:
    """Per row: the target if some bin reaches it, else the floor if reached, else the best."""
    best = sl_db.max(axis=-1)
    return np.where(best >= target_sl_db, target_sl_db, np.where(best >= floor_db, floor_db, best))


def choose_bins(
    active_um_per_v: np.ndarray,
    ratio: np.ndarray,
    freq_hz: np.ndarray,
    perception: Perception,
    cap_v: float,
    target_sl_db: float,
    site: str = "fingertip",
) -> np.ndarray:
    """(N,) bin index per row of (N, K): best ``ratio`` where the active level at
    ``cap_v`` reaches the sensation level (tiers: target, 3 JND, strongest bin)."""
    thr = perception.threshold_db(freq_hz, site)
    with np.errstate(divide="ignore"):
        sl = 20 * np.log10(np.maximum(active_um_per_v, 1e-300) * cap_v) - thr
    req = _required_sl(sl, target_sl_db, 3 * perception.jnd_db)
    score = np.where(sl >= req[..., None] - 1e-9, ratio, -np.inf)
    return score.argmax(axis=-1)


def solve_pairs(
    m: VibrationMap,
    pairs: Iterable[tuple[int, int]],
    perception: Perception,
    *,
    cap_v: float,
    target_sl_db: float = 20.0,
    band_hz: float = 650.0,
    method: str = "independent",
    map_error_rel: float = DEFAULT_MAP_ERROR_REL,
    eps: np.ndarray | None = None,
) -> list[dict]:
    """One answer per (active, passive) pair of map INDICES: ``frequency_hz``, ``bin``,
    ``weights`` (4,) complex (1 V peak on the strongest patch), ``active_um_per_v``,
    ``passive_um_per_v`` (at those weights, per volt of drive), ``contrast_db`` (the
    map's) and ``expected_contrast_db`` (with the map error ``eps``), ``amplitude_v``
    (drive for the target level, at most ``cap_v``) and ``sensation_level_db``.
    ``eps`` (F,): the error variance per map bin (default from ``map_error_rel``)."""
    if method not in METHODS:
        raise UserError(f"method {method!r}: use {', '.join(METHODS)}")
    pairs = [(int(a), int(b)) for a, b in pairs]
    keep = usable_bins(m, band_hz)
    h = patch_frf(m, keep)  # (4, P, K)
    eps = error_variance(h, map_error_rel) if eps is None else eps[keep]
    f = m.freq_hz[keep]
    hp = np.ascontiguousarray(h.transpose(1, 2, 0))  # (P, K, 4)
    by_active: dict[int, list[int]] = {}
    for i, (a, b) in enumerate(pairs):
        if a == b:
            raise UserError(f"pair {a}->{b}: the active and passive points are the same")
        by_active.setdefault(a, []).append(i)
    out: list[dict] = [{} for _ in pairs]
    for a, rows in by_active.items():
        bs = np.array([pairs[i][1] for i in rows])
        for s in range(0, bs.size, 16):
            chunk = bs[s : s + 16]
            ha = hp[a][None]  # (1, K, 4)
            hb = hp[chunk]  # (n, K, 4)
            x = np.broadcast_to(pair_weights(ha, hb, eps, method), hb.shape)  # (n, K, 4)
            ga = np.abs(np.sum(ha * x, axis=-1))
            gb = np.abs(np.sum(hb * x, axis=-1))
            ratio = ga**2 / (gb**2 + eps * np.sum(np.abs(x) ** 2, axis=-1))
            k = choose_bins(ga, ratio, f, perception, cap_v, target_sl_db)
            for j, i in enumerate(rows[s : s + 16]):
                kk = int(k[j])
                out[i] = _answer(
                    method, float(f[kk]), int(keep[kk]), x[j, kk], ga[j, kk], gb[j, kk],
                    ratio[j, kk], perception, cap_v, target_sl_db, "fingertip",
                )  # fmt: skip
    return out


def _answer(method, f, k, x, ga, gb, ratio, perception, cap_v, target_sl_db, site) -> dict:
    thr = float(perception.threshold_db(f, site))
    ga, gb = float(ga), float(gb)
    amp = min(10 ** ((thr + target_sl_db) / 20) / max(ga, 1e-300), cap_v)
    return {
        "method": method,
        "frequency_hz": f,
        "bin": k,
        "weights": np.asarray(x, complex),
        "active_um_per_v": ga,
        "passive_um_per_v": gb,
        "contrast_db": float(20 * math.log10(max(ga, 1e-300) / max(gb, 1e-300))),
        "expected_contrast_db": float(10 * math.log10(max(float(ratio), 1e-300))),
        "amplitude_v": float(amp),
        "threshold_db": thr,
        "sensation_level_db": float(20 * math.log10(max(ga * amp, 1e-300)) - thr),
    }


# --------------------------------------------------------------------------- hand
def side_points(squares: int, n: int, side: np.ndarray) -> np.ndarray:
    """Flat indices (row-major over the (squares n) x (squares n) lattice) of the
    subgrid points of the squares in ``side`` (squares, squares) [row(y), col(x)]."""
    sq = np.arange(squares * n) // n
    rows, cols = np.meshgrid(sq, sq, indexing="ij")
    return np.flatnonzero(side[rows, cols])


def square_levels_of(amp: np.ndarray, squares: int, n: int) -> np.ndarray:
    """(..., squares, squares) level per square: the ceil(n^2/2)-th largest of its
    subgrid amplitudes (``amp`` (..., (squares n)^2) row-major), paper 5.2.2."""
    lead = amp.shape[:-1]
    a = amp.reshape(*lead, squares, n, squares, n)
    a = np.moveaxis(a, -3, -2).reshape(*lead, squares, squares, n * n)
    rank = math.ceil(n * n / 2)
    return -np.partition(-a, rank - 1, axis=-1)[..., rank - 1]


def max_min_weights(
    h: np.ndarray,
    side_a: np.ndarray,
    side_b: np.ndarray,
    squares: int,
    n: int,
    eps: float,
    iterations: int = 12,
) -> tuple[np.ndarray, float]:
    """Max-min drive for one bin: maximise (weakest active square level) / (strongest
    passive square level). ``h`` (points, 4) FRFs on the lattice. Starts from the summed
    generalised eigenproblem and reweights squares (weak active and strong passive
    squares gain weight), keeping the best. Returns (x peak-scaled, contrast in dB)."""
    sq_of = (np.arange(squares * n)[:, None] // n) * squares + (np.arange(squares * n)[None] // n)
    sq_of = sq_of.ravel()
    act = np.flatnonzero(side_a.ravel())
    pas = np.flatnonzero(side_b.ravel())
    outer = np.einsum("pi,pj->pij", np.conj(h), h)  # (points, 4, 4)
    per_sq = np.stack([outer[sq_of == s].mean(axis=0) for s in range(squares * squares)])
    wa, wb = np.ones(act.size), np.ones(pas.size)
    best_x, best_c = None, -np.inf
    eye = np.eye(h.shape[1])
    for _ in range(iterations):
        a = np.tensordot(wa, per_sq[act], axes=1)
        b = np.tensordot(wb, per_sq[pas], axes=1) + eps * eye
        x, _ = generalized_max(a, b)
        lv = square_levels_of(np.abs(h @ x), squares, n).ravel()
        la, lb = lv[act], lv[pas]
        c = 20 * math.log10(max(la.min(), 1e-300) / max(lb.max(), 1e-300))
        if c > best_c:
            best_x, best_c = x, c
        wa = wa * np.maximum(la.min() / np.maximum(la, 1e-300), 1e-3)
        wb = wb * np.maximum(lb / max(lb.max(), 1e-300), 1e-3)
        wa, wb = wa / wa.sum(), wb / wb.sum()
    return scale_to_peak(best_x), best_c


def region_lattice(
    center_mm, hand_mm: float, squares: int, subgrid: int, stride: int
) -> tuple[np.ndarray, np.ndarray, int]:
    """(xs, ys, n): the lattice of the hand's subgrid points kept at ``stride`` (n per
    square per axis), centred on ``center_mm`` (as ``hand.square_levels``)."""
    sub = hand_mm / (squares * subgrid)
    local = np.arange(subgrid)[stride // 2 :: stride]
    offs = (
        (np.arange(squares)[:, None] * subgrid + local[None, :]).ravel() + 0.5
    ) * sub - hand_mm / 2
    return float(center_mm[0]) + offs, float(center_mm[1]) + offs, int(local.size)


def solve_region(
    m: VibrationMap,
    center_mm,
    direction: str,
    perception: Perception,
    *,
    cap_v: float,
    hand_mm: float = 120.0,
    squares: int = 3,
    subgrid: int = 15,
    band_hz: float = 650.0,
    method: str = "independent",
    map_error_rel: float = DEFAULT_MAP_ERROR_REL,
    interpolation: str = "spline",
    stride: int = 3,
    candidates: int = 6,
    objective: str = "max_min",
) -> list[dict]:
    """The two parts of a flow under a hand (part 1: start side active, end side
    passive; part 2 the reverse), each: ``frequency_hz``, ``bin``, ``weights`` (4,),
    ``contrast_db`` (strongest active / strongest passive square, the paper's margin),
    ``min_active_contrast_db`` (weakest active / strongest passive), ``x_um`` (the
    3-JND line of the palm), ``amplitude_v`` (the weakest active square 6 dB above the
    line, at most ``cap_v``). ``independent``: the summed generalised eigenproblem per
    bin, then the max-min reweighting on the best ``candidates`` bins; ``time_reversal``:
    the drive of most energy on the active side (the principal eigenvector of A)."""

    if method not in METHODS:
        raise UserError(f"method {method!r}: use {', '.join(METHODS)}")
    keep = usable_bins(m, band_hz)
    patch_frf(m, keep)  # the checks (missing patch, not finite)
    idx = [m.excitations.index(p) for p in PATCHES]
    xs, ys, n = region_lattice(center_mm, hand_mm, squares, subgrid, stride)
    band = np.ascontiguousarray(m.frf_um_per_v[idx][:, :, keep].astype(np.complex64))
    h = interpolate_lattice(m, xs, ys, interpolation, frf=band, cache=False)  # (4, Ny, Nx, K)
    h = np.ascontiguousarray(h.reshape(4, -1, keep.size).transpose(2, 1, 0)).astype(complex)
    eps = error_variance(h.transpose(2, 1, 0), map_error_rel)  # (K,)
    f = m.freq_hz[keep]
    x_um = perception.threshold_um(f, "palm") * 10 ** (3 * perception.jnd_db / 20)
    start, end = side_masks(direction, squares)
    parts = []
    for side_a, side_b in ((start, end), (end, start)):
        pa, pb = side_points(squares, n, side_a), side_points(squares, n, side_b)
        a = np.einsum("kpi,kpj->kij", np.conj(h[:, pa]), h[:, pa]) / pa.size
        b = np.einsum("kpi,kpj->kij", np.conj(h[:, pb]), h[:, pb]) / pb.size
        if method == "independent":
            x, _ = generalized_max_batched(a, b + eps[:, None, None] * np.eye(4))
        else:
            x = np.linalg.eigh(a)[1][..., -1]
        x = scale_to_peak(x)
        lv = square_levels_of(np.abs(np.einsum("kpi,ki->kp", h, x)), squares, n)
        la, lb = lv[:, side_a], lv[:, side_b]
        with np.errstate(divide="ignore"):
            top = la.min(axis=1) if objective == "max_min" else la.max(axis=1)
            mm = 20 * np.log10(top / np.maximum(lb.max(axis=1), 1e-300))
            sl = 20 * np.log10(np.maximum(la.min(axis=1), 1e-300) * cap_v / x_um)
        req = _required_sl(sl[None], 0.0, -np.inf)[0]
        score = np.where(sl >= req - 1e-9, mm, -np.inf)
        order = np.argsort(score)[::-1][: max(1, candidates)]
        best = (-np.inf, int(order[0]), x[order[0]])
        for k in order:
            if not np.isfinite(score[k]):
                break
            xk, ck = x[k], score[k]
            if method == "independent" and objective == "max_min":
                xr, cr = max_min_weights(h[k], side_a, side_b, squares, n, float(eps[k]))
                lr = square_levels_of(np.abs(h[k] @ xr), squares, n)
                if cr > ck and lr[side_a].min() * cap_v >= x_um[k] * 10 ** (req / 20) - 1e-12:
                    xk, ck = xr, cr
            if ck > best[0]:
                best = (ck, int(k), xk)
        _, k, xk = best
        lv = square_levels_of(np.abs(h[k] @ xk), squares, n)
        la, lb = lv[side_a], lv[side_b]
        amp = float(min(cap_v, 2.0 * x_um[k] / max(la.min(), 1e-300)))
        parts.append(
            {
                "method": method,
                "frequency_hz": float(f[k]),
                "bin": int(keep[k]),
                "weights": np.asarray(xk, complex),
                "levels_um_per_v": lv,
                "contrast_db": float(20 * math.log10(la.max() / max(lb.max(), 1e-300))),
                "min_active_contrast_db": float(
                    20 * math.log10(max(la.min(), 1e-300) / max(lb.max(), 1e-300))
                ),
                "x_um": float(x_um[k]),
                "amplitude_v": amp,
                "objective": objective,
            }
        )
    return parts


# --------------------------------------------------------------------------- uniform drives
def actuator_weights(actuator: str) -> np.ndarray:
    """(4,) drive of the paper's excitation: one patch at 1, or PALL all four at 1."""
    if actuator == "PALL":
        return np.ones(4, complex)
    if actuator not in PATCHES:
        raise UserError(f"actuator {actuator!r}: use {', '.join(PATCHES)} or PALL")
    x = np.zeros(4, complex)
    x[PATCHES.index(actuator)] = 1.0
    return x


def paper_pair_drives(
    t, pairs: Iterable[tuple[int, int]], perception: Perception, *, cap_v: float,
    target_sl_db: float = 20.0,
) -> list[dict | None]:  # fmt: skip
    """The tables' answer per pair of map indices in the form of ``solve_pairs`` (weights
    of the table's actuator at 1 V); ``None`` where the tables have no flow."""
    m = t.vmap
    keep = usable_bins(m, t.band_hz)
    h = patch_frf(m)
    out: list[dict | None] = []
    for a, b in pairs:
        if not t.max_diff_um_per_v[a, b] > 0:
            out.append(None)
            continue
        act = m.excitations[int(t.actuator[a, b])]
        f = float(t.freq_hz[a, b])
        k = int(keep[np.argmin(np.abs(m.freq_hz[keep] - f))])
        x = actuator_weights(act)
        ga, gb = abs(h[:, a, k] @ x), abs(h[:, b, k] @ x)
        ans = _answer("paper", f, k, x, ga, gb, ga**2 / max(gb**2, 1e-300), perception, cap_v,
                      target_sl_db, "fingertip")  # fmt: skip
        ans["actuator"] = act
        out.append(ans)
    return out


__all__ = [
    "actuator_weights",
    "paper_pair_drives",
    "region_lattice",
    "solve_region",
    "METHODS",
    "PATCHES",
    "choose_bins",
    "error_variance",
    "focus_weights",
    "generalized_max",
    "generalized_max_batched",
    "max_min_weights",
    "pair_weights",
    "patch_frf",
    "scale_to_peak",
    "side_points",
    "solve_pairs",
    "square_levels_of",
]
