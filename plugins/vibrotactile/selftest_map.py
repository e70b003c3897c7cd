"""The self-test against the stored vibration map: faults found on a table's first test.

Without an earlier self-test the baseline is the map the profile uses (its measured or
imported map, or ``[selftest] map``) at the reference point: each excitation's
displacement FRF there (um per volt at the patches) as acceleration, ``-(2 pi f)^2 x 1e-6``
(m/s^2 per volt). A laser map was measured without the sensor on the glass; the self-test's
accelerometer loads the plate at its own point. A point mass m at the sensor's point j
changes every path's FRF there by the same factor (structural modification, see
``mass_correction``): ``H^m_jp = H_jp / (1 - m w^2 H_jj)``, so

    H_p(f) = g(f) sum_q c_pq B_q(f)

with one unknown complex factor g(f) shared by the four single paths. It is fitted with the
mix c by alternating least squares (c per path over the band given g; g per bin over the
paths given c, scaled to a median of 1 so the mix keeps the level: away from the loaded
modes g ~ 1), from g = 1; a silent,
swapped or stuck path fits c and leaves g to the others. A map measured with the same
roving sensor gives g ~ 1. The result is read by ``selftest.findings`` as any mix.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from console.plugin_api import EXCITATIONS, PATCHES, UserError
from plugins.vibrotactile.selftest_shape import SILENT, kept_db, on_freqs, spread_db

#: the alternating fit's iterations (it settles in ~5 on the twin's tables)
ITERATIONS = 25


def map_baseline(vmap: Any, ref: tuple[int, float, float], band_hz: tuple[float, float]) -> dict:
    """The map at the reference point as a baseline (acceleration per volt, every path)."""
    missing = [e for e in EXCITATIONS if e not in vmap.excitations]
    if missing:
        raise UserError(
            f"vibration map: no {', '.join(missing)} in it; the self-test against the map "
            "needs PA PB PC PD PALL: measure the map again or run `haptable selftest "
            "--save-baseline` on a healthy table"
        )
    d = np.hypot(*(np.asarray(vmap.points_mm, float) - np.array(ref[1:])).T)
    k = int(np.argmin(d))
    if d[k] > 1.0:
        raise UserError(
            f"vibration map: no point at the reference point {ref[0]} ({ref[1]:.0f}, "
            f"{ref[2]:.0f}) mm (nearest {d[k]:.0f} mm away); set [selftest] reference_point "
            "to one of the map's points"
        )
    f = np.asarray(vmap.freq_hz, float)
    if f.min() > band_hz[0] or f.max() < band_hz[1]:
        raise UserError(
            f"vibration map: {f.min():.0f}-{f.max():.0f} Hz does not cover the self-test's "
            f"{band_hz[0]:.0f}-{band_hz[1]:.0f} Hz; measure the map over it"
        )
    rows = np.array([vmap.frf_um_per_v[vmap.excitations.index(e), k] for e in EXCITATIONS])
    h = -((2 * math.pi * f) ** 2) * rows * 1e-6
    return {
        "paths": np.array(EXCITATIONS),
        "freqs_hz": f,
        "h": h,
        "reference": np.array(ref, float),
        "point_id": int(vmap.points[k]),
    }


def _fit_c(basis_g: np.ndarray, h4: np.ndarray) -> np.ndarray:
    return np.array([np.linalg.lstsq(basis_g.T, row, rcond=None)[0] for row in h4])


def mix_with_sensor(got: dict[str, Any], base: dict[str, Any]) -> dict[str, Any]:
    """As ``selftest.mix`` with the sensor's common factor g(f) fitted too; also ``g``."""
    freqs = got["freqs_hz"]
    b = on_freqs(freqs, base["freqs_hz"], base["h"])
    bp = {str(p): b[i] for i, p in enumerate(base["paths"])}
    basis = np.array([bp[p] for p in PATCHES])  # (4, F)
    h = {str(p): got["h"][i] for i, p in enumerate(got["paths"])}
    h4 = np.array([h[p] for p in PATCHES])
    g = np.ones(freqs.size, complex)
    # a silent path (a dead channel, a relay stuck open) carries noise only: it fits no g
    moving = np.abs(_fit_c(basis, h4)).max(axis=1) >= SILENT
    for _ in range(ITERATIONS if moving.any() else 0):
        c = _fit_c(basis * g, h4)
        c[~moving] = 0.0
        model = c @ basis  # (4, F): each path without the sensor's factor
        den = np.sum(np.abs(model) ** 2, axis=0)
        num = np.sum(np.conj(model) * h4, axis=0)
        ok = den > 1e-12 * max(float(den.max()), 1e-300)
        g_new = np.where(ok, num / np.where(ok, den, 1.0), 1.0)
        scale = np.median(g_new.real) + 1j * np.median(g_new.imag)
        if not np.isfinite(scale) or abs(scale) < 1e-9:  # nothing moves: no factor to fit
            g = np.ones_like(g)
            break
        g_new = g_new / scale
        done = np.max(np.abs(g_new - g)) < 1e-6
        g = g_new
        if done:
            break
    bg = basis * g
    c = _fit_c(bg, h4)
    residual = np.array(
        [np.linalg.norm(h4[i] - bg.T @ c[i]) / np.linalg.norm(bg[i]) for i in range(4)]
    )
    pall_db = None
    if "PALL" in h and "PALL" in bp:  # against the single paths' fits together (g's scale)
        pall = (c @ bg).sum(axis=0)
        pall_db = 20 * math.log10(np.linalg.norm(h["PALL"]) / np.linalg.norm(pall))
    return {
        "c": c,
        "residual": residual,
        "pall_db": pall_db,
        "spread_db": spread_db(freqs, h4, c @ bg),
        "kept_db": kept_db(freqs, h4, bg),
        "g": g,
    }
