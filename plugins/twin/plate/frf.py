"""Modal frequency response of the plate: displacement per volt at the patch terminals.

H(x, f) = sum_r phi_r(x) Q_r / (omega_r^2 - omega^2 + 2 j zeta_r omega_r omega) [+ R(x)]

with mass-normalised modes phi_r, modal forces Q_r (``piezo.modal_forces``) and modal
damping zeta_r. The optional quasi-static residual R(x) adds the static response of the
modes left out (K^-1 f minus the kept modes' static part), which removes most of the
truncation error below the first dropped mode at no cost per frequency.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import linalg

from .ritz import Modes


def modal_receptance(
    omega_r: np.ndarray, freqs_hz: np.ndarray, zeta: float | np.ndarray
) -> np.ndarray:
    """G[r, f] = 1 / (omega_r^2 - omega^2 + 2 j zeta omega_r omega): (R, F)."""
    w = 2.0 * math.pi * np.asarray(freqs_hz, dtype=float)[None, :]
    wr = np.asarray(omega_r, dtype=float)[:, None]
    z = np.broadcast_to(np.asarray(zeta, dtype=float), omega_r.shape)[:, None]
    return 1.0 / (wr**2 - w**2 + 2j * z * wr * w)


def static_residual(modes: Modes, loads: np.ndarray, q: np.ndarray) -> np.ndarray | None:
    """Coefficients of the static response of the modes NOT in ``modes``: (E, mx, my).

    K^-1 f_e minus sum over kept modes of phi_r Q_re / omega_r^2. None when the plate
    has rigid-body modes (K singular: a free plate), where no static response exists.
    """
    if modes.n_rigid:
        return None
    sysm = modes.system
    f = loads.reshape(loads.shape[0], -1).T  # (n, E)
    full = linalg.solve(sysm.k, f, assume_a="pos")  # (n, E)
    c = modes.coeffs.reshape(modes.coeffs.shape[0], -1)  # (R, n)
    kept = c.T @ (q / modes.omega_rad_s[:, None] ** 2)  # (n, E)
    return (full - kept).T.reshape(loads.shape)


def displacement_frf(
    phi: np.ndarray,
    q: np.ndarray,
    omega_r: np.ndarray,
    freqs_hz: np.ndarray,
    zeta: float | np.ndarray = 0.01,
    residual: np.ndarray | None = None,
) -> np.ndarray:
    """Displacement FRF (E, P, F) complex, in metres per volt.

    ``phi`` (P, R) mode shapes at the points, ``q`` (R, E) modal forces per volt,
    ``residual`` (E, P) static residual displacement per volt at the points (or None).
    """
    g = modal_receptance(omega_r, freqs_hz, zeta)  # (R, F)
    out = np.einsum("pr,re,rf->epf", phi, q, g, optimize=True)
    if residual is not None:
        out += residual[:, :, None]
    return out


def grid_peak_factor(
    freqs_hz: np.ndarray, f_n_hz: np.ndarray, zeta: float | np.ndarray
) -> np.ndarray:
    """Fraction of each resonance peak a discrete frequency grid keeps (FACTS).

    The nearest bin sits d = |f_bin - f_n| from resonance, which scales the peak by
    1 / sqrt(1 + (d / (zeta f_n))^2). Keep df <= 0.5 zeta f_n for < 3 % loss.
    """
    grid = np.sort(np.asarray(freqs_hz, dtype=float))
    f_n = np.atleast_1d(np.asarray(f_n_hz, dtype=float))
    i = np.clip(np.searchsorted(grid, f_n), 1, grid.size - 1)
    d = np.minimum(np.abs(grid[i] - f_n), np.abs(grid[i - 1] - f_n))
    return 1.0 / np.sqrt(1.0 + (d / (np.asarray(zeta) * f_n)) ** 2)


def missed_peaks(
    freqs_hz: np.ndarray, f_n_hz: np.ndarray, zeta: float, max_loss: float = 0.03
) -> list[dict]:
    """Resonances inside the grid's span whose peak the grid underestimates by > max_loss."""
    grid = np.asarray(freqs_hz, dtype=float)
    f_n = np.asarray(f_n_hz, dtype=float)
    inside = f_n[(f_n >= grid.min()) & (f_n <= grid.max()) & (f_n > 0)]
    factor = grid_peak_factor(grid, inside, zeta)
    return [
        {"mode_hz": float(f), "peak_kept": float(k), "half_power_bandwidth_hz": 2 * zeta * f}
        for f, k in zip(inside, factor, strict=True)
        if k < 1 - max_loss
    ]
