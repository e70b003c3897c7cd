"""How far a self-test path's FRF changed shape: its level against the fit, band by band.

A detached patch keeps its FRF's shape (it only shakes the glass less: every band drops
alike); a cracked one does not (``plugins.twin.crack``: flat at the area left below the
crack's resonance, raised around it, falling above). The fit ``M = c B`` of a path (its mix
of the baseline's paths) has the right overall level; the spread of ``20 log10(|<H, M>_b|
/ |M|_b^2)`` (the part of H along M: noise averages out) over a few bands (about an octave and a half each over 40-625 Hz) is then ~0
dB for a healthy, detached or stuck path and several dB for a cracked one. The sensor's
noise spreads a very weak path's levels too (a detached patch's 2-10 %), so a crack also
needs one band near its full level (``kept_db``: a cracked patch keeps the area left there,
-4.4 dB on the twin; a detached one is 20 dB and more down in every band).
"""

from __future__ import annotations

import numpy as np

#: a path's mix below this moves nothing (-46 dB; noise alone gives ~1e-4; ``Thresholds``)
SILENT = 0.005
#: the bands (Hz) the level is compared in
BANDS_HZ = ((40.0, 100.0), (100.0, 250.0), (250.0, 625.0))


def band_db(freqs_hz: np.ndarray, h: np.ndarray, model: np.ndarray) -> np.ndarray:
    """Rows ``h`` (R, F) against ``model`` (R, F): (R, bands) dB, NaN where a band is
    empty or the model silent there."""
    f = np.asarray(freqs_hz)
    out = np.full((h.shape[0], len(BANDS_HZ)), np.nan)
    for k, (lo, hi) in enumerate(BANDS_HZ):
        sel = (f >= lo) & (f < hi)
        if not sel.any():
            continue
        # the part of h along the model (noise, uncorrelated with it, averages out)
        num = np.abs(np.sum(np.conj(model[:, sel]) * h[:, sel], axis=1))
        den = np.sum(np.abs(model[:, sel]) ** 2, axis=1)
        ok = (den > 0) & (num > 0)
        out[ok, k] = 20 * np.log10(num[ok] / den[ok])
    return out


def spread_db(freqs_hz: np.ndarray, h: np.ndarray, model: np.ndarray) -> np.ndarray:
    """(R,) the largest minus the smallest band level of each row (0: shape kept)."""
    b = band_db(freqs_hz, h, model)
    hi = np.where(np.isnan(b), -np.inf, b).max(axis=1)
    lo = np.where(np.isnan(b), np.inf, b).min(axis=1)
    return np.where(np.isfinite(hi - lo), hi - lo, 0.0)


def kept_db(freqs_hz: np.ndarray, h: np.ndarray, base: np.ndarray) -> np.ndarray:
    """(R,) each row's loudest band against the baseline's same path (0 dB: kept)."""
    b = band_db(freqs_hz, h, base)
    return np.where(np.isnan(b), -np.inf, b).max(axis=1)


def on_freqs(freqs: np.ndarray, f: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Complex ``h`` (rows on ``f``) on ``freqs`` (real and imaginary parts apart)."""
    if f.shape == freqs.shape and np.allclose(f, freqs):
        return h
    return np.array([np.interp(freqs, f, r.real) + 1j * np.interp(freqs, f, r.imag) for r in h])
