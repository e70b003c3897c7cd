"""A sensor glued on the plate twin: its mass on the modal model, its acceleration.

A roving accelerometer of m kg at (x0, y0) adds the point mass m w(x0, y0)^2 to the
plate's kinetic energy: the mass matrix becomes M' = M + m v v^T (v the Ritz basis at the
sensor) and the modes are solved again on the unloaded modes up to ``REDUCE_MARGIN`` x the
kept band (``with_point_mass``; the patches' modal forces and the static residual follow
the new modes). Modes shift down, most where the sensor sits on an
antinode; first order (Rayleigh) omega_r'^2 = omega_r^2 / (1 + m phi_r(x0)^2) for
mass-normalised phi_r (tests/instrument checks the solve against it).

``acceleration`` is the plate's out-of-plane acceleration at a point for the volts on each
patch, from rest: the displacement FRF (modes + static residual) times -(2 pi f)^2,
convolved with zero-padded FFTs long enough for the slowest mode to ring out (as the
twin vibrometer does for velocity: exact for the sampled input).
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import replace

import numpy as np
from scipy import fft as sfft
from scipy import linalg

from .frf import modal_receptance, static_residual
from .model import EXCITATIONS, Twin, _eval_coeffs, build_twin
from .piezo import modal_forces, patch_loads
from .ritz import Modes

#: ring-down kept after the input, in decay times 1 / (zeta omega_min) (e^-12: below noise)
RING_DECAYS = 12.0

#: the mass-loaded modes are solved on the unloaded modes up to this x the twin's kept band
#: (a Ritz reduction: 4 x keeps every shift within ~0.02 Hz of the full basis' solve)
REDUCE_MARGIN = 4.0

_CACHE: OrderedDict[tuple, Twin] = OrderedDict()
_ALL: OrderedDict[str, tuple[np.ndarray, np.ndarray]] = OrderedDict()


def _all_modes(twin: Twin) -> tuple[np.ndarray, np.ndarray]:
    """(omega^2 (N,), coefficient vectors (n, N)) of every mode of the Ritz basis (cached)."""
    hit = _ALL.get(twin.key)
    if hit is None:
        sysm = twin.modes.system
        lam, vec = linalg.eigh(sysm.k)
        hit = (lam / sysm.m_scale, vec / math.sqrt(sysm.m_scale))
        _ALL[twin.key] = hit
        if len(_ALL) > 4:
            _ALL.popitem(last=False)
    return hit


def _basis_at(twin: Twin, x_mm: float, y_mm: float) -> np.ndarray:
    s = twin.modes.system
    xi = np.array([2 * x_mm / 1e3 / s.plate.a_m - 1])
    eta = np.array([2 * y_mm / 1e3 / s.plate.b_m - 1])
    if abs(xi[0]) > 1 + 1e-9 or abs(eta[0]) > 1 + 1e-9:
        raise ValueError(f"sensor at ({x_mm:g}, {y_mm:g}) mm is outside the plate")
    return np.outer(s.bx.values(xi)[0], s.by.values(eta)[0]).ravel()


def with_point_mass(twin: Twin, x_mm: float, y_mm: float, mass_kg: float) -> Twin:
    """The twin with a point mass at (x_mm, y_mm) (cached by position and mass)."""
    if mass_kg <= 0:
        return twin
    key = (twin.key, round(float(x_mm), 3), round(float(y_mm), 3), round(float(mass_kg), 9))
    hit = _CACHE.get(key)
    if hit is not None:
        _CACHE.move_to_end(key)
        return hit
    sysm = twin.modes.system
    w2, phi = _all_modes(twin)  # every Ritz mode, unloaded, mass-normalised
    keep = w2 <= (2 * math.pi * REDUCE_MARGIN * twin.params.f_keep_hz) ** 2
    psi = _basis_at(twin, x_mm, y_mm) @ phi[:, keep]  # the modes at the sensor
    evals, evecs = linalg.eigh(np.diag(w2[keep]), np.eye(psi.size) + mass_kg * np.outer(psi, psi))
    inside = evals <= (2 * math.pi * twin.params.f_keep_hz) ** 2
    omega = np.sqrt(np.clip(evals[inside], 0.0, None))
    coeffs = (phi[:, keep] @ evecs[:, inside]).T  # phi'^T M' phi' = 1
    mx, my = sysm.bx.t.shape[1], sysm.by.t.shape[1]
    modes = Modes(sysm, omega, coeffs.reshape(-1, mx, my), twin.modes.n_rigid, "")
    p = twin.params
    loads = patch_loads(sysm, list(p.patches), p.moment_n_per_v)
    loads = np.concatenate([loads, loads.sum(axis=0, keepdims=True)])
    q = modal_forces(modes, loads)
    res = static_residual(modes, loads, q) if p.static_residual else None
    out = replace(twin, modes=modes, q=q, residual_coeffs=res, key=f"{twin.key}+{key[1:]}")
    _CACHE[key] = out
    if len(_CACHE) > 128:
        _CACHE.popitem(last=False)
    return out


def rayleigh_freq_hz(twin: Twin, x_mm: float, y_mm: float, mass_kg: float) -> np.ndarray:
    """First-order mode frequencies with the point mass: f_r / sqrt(1 + m phi_r^2)."""
    phi = twin.modes.shapes(np.array([x_mm / 1e3]), np.array([y_mm / 1e3]))[0]
    return twin.freq_hz / np.sqrt(1.0 + mass_kg * phi**2)


def accel_frf(twin: Twin, x_mm: float, y_mm: float, freqs_hz: np.ndarray) -> np.ndarray:
    """Acceleration per volt on each patch PA..PD at a point: (4, F) complex, m/s^2/V."""
    x_m, y_m = np.array([x_mm / 1e3]), np.array([y_mm / 1e3])
    phi = twin.modes.shapes(x_m, y_m)[0]  # (R,)
    g = modal_receptance(twin.modes.omega_rad_s, freqs_hz, twin.params.damping_ratio)
    disp = np.einsum("r,re,rf->ef", phi, twin.q[:, :4], g)
    if twin.residual_coeffs is not None:
        disp = disp + _eval_coeffs(twin, twin.residual_coeffs[:4], x_m, y_m)[:, :1]
    return -((2 * math.pi * np.asarray(freqs_hz)) ** 2) * disp


def ring_samples(twin: Twin, fs_hz: float) -> int:
    """Samples for the slowest mode to ring out (``RING_DECAYS`` decay times)."""
    w_min = float(twin.modes.omega_rad_s[twin.modes.n_rigid :].min())
    return int(math.ceil(RING_DECAYS / (twin.params.damping_ratio * w_min) * fs_hz))


def acceleration(
    twin: Twin, x_mm: float, y_mm: float, patch_v: np.ndarray, fs_hz: float
) -> np.ndarray:
    """Acceleration (N,) m/s^2 at (x_mm, y_mm) for volts ``patch_v`` (4, N) on PA..PD, from
    rest (rows of zeros cost nothing)."""
    patch_v = np.asarray(patch_v, dtype=float)
    n = patch_v.shape[1]
    used = [i for i in range(4) if np.any(patch_v[i])]
    if not used or n == 0:
        return np.zeros(n)
    npad = sfft.next_fast_len(n + ring_samples(twin, fs_hz), real=True)
    f = sfft.rfftfreq(npad, 1 / fs_hz)
    h = accel_frf(twin, x_mm, y_mm, f)
    spec = sum(h[i] * sfft.rfft(patch_v[i], npad) for i in used)
    return sfft.irfft(spec, npad)[:n]


def patch_index(name: str) -> int:
    """PA..PD -> 0..3."""
    return EXCITATIONS.index(name)


__all__ = [
    "acceleration",
    "accel_frf",
    "build_twin",
    "patch_index",
    "rayleigh_freq_hz",
    "ring_samples",
    "with_point_mass",
]
