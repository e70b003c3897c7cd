"""Ring-down between flow parts: how long the plate keeps vibrating after a part stops.

After a tone near a mode at ``f_n`` with modal damping ``zeta`` stops, that mode decays
as ``exp(-t / tau)`` with ``tau = 1 / (2 pi zeta f_n)`` (0.3 s at 53 Hz, 1 %). Part 2's
passive point is part 1's active point, so with the relay gap alone (milliseconds) a
low-frequency part 1 still rings when part 2 starts. The ring-down-aware gap is
``k x tau`` of part 1's mode: after ``k`` decay times the ring is ``8.7 k`` dB down
(part 1 at ``SL`` dB above threshold falls below it for ``k >= SL / 8.7``).

``zeta`` comes from the map's half-power bandwidth (``2 zeta f_n = f_2 - f_1`` where
the spatial RMS of ``|H|`` is ``peak / sqrt 2``) of the mode contributing most at the
part's frequency, or from a given value when no peak is resolved.
"""

from __future__ import annotations

import math

import numpy as np

from console.plugin_api import VibrationMap


def resonances(r: np.ndarray, f: np.ndarray) -> list[tuple[float, float, float]]:
    """Resolved resonance peaks of a magnitude curve ``r(f)``: ``(f_n, zeta_n, height)``.

    A peak counts when ``r`` falls below ``peak / sqrt 2`` on both sides before rising
    above the peak (so measurement ripple is no peak) and the half-power band spans at
    least 3 bins; ``zeta_n = (f_2 - f_1) / (2 f_n)``, crossings interpolated linearly.
    """
    out = []
    if r.size < 3:
        return out
    cand = np.flatnonzero((r[1:-1] > r[:-2]) & (r[1:-1] >= r[2:])) + 1
    df = float(np.median(np.diff(f)))
    for k in cand:
        half = r[k] / math.sqrt(2)
        cross = []
        for step in (-1, 1):
            j = k
            while 0 <= j + step < r.size and half <= r[j + step] <= r[k]:
                j += step
            if not 0 <= j + step < r.size or r[j + step] > r[k]:
                break  # ran off the curve or into a higher peak: not resolved
            t = (r[j] - half) / max(r[j] - r[j + step], 1e-300)
            cross.append(float(f[j] + t * (f[j + step] - f[j])))
        if len(cross) == 2 and cross[1] - cross[0] >= 3 * df:
            fn = float(f[k])
            out.append((fn, (cross[1] - cross[0]) / (2 * fn), float(r[k])))
    return out


def half_power_zeta(
    m: VibrationMap, excitation: str, freq_hz: float, *, band_hz: float = 650.0
) -> tuple[float, float] | None:
    """``(f_n, zeta)`` of the mode that rings after a tone at ``freq_hz``: among the
    resolved peaks (``resonances``) of the spatial RMS of the excitation's ``|H|``, the
    one contributing most at ``freq_hz`` (single-mode magnitude
    ``height / sqrt(1 + ((f - f_n) / (zeta f_n))^2)``). ``None`` when the resolved peaks
    explain less than half the response at ``freq_hz`` (the lines are too coarse for the
    damping of the mode that rings there)."""
    # lazy: SciPy loads only when this runs
    from plugins.vibrotactile.tables import usable_bins

    keep = usable_bins(m, max(band_hz, float(freq_hz)))
    f = m.freq_hz[keep]
    e = m.excitation_index(excitation)
    r = np.sqrt(np.mean(np.abs(m.frf_um_per_v[e][:, keep]) ** 2, axis=0))
    peaks = resonances(r, f)
    if not peaks:
        return None
    share = [h / math.sqrt(1 + ((freq_hz - fn) / (z * fn)) ** 2) for fn, z, h in peaks]
    best = int(np.argmax(share))
    if share[best] < 0.5 * float(np.interp(freq_hz, f, r)):
        return None  # the response there comes from modes the lines do not resolve
    fn, z, _ = peaks[best]
    return fn, z


def decay_time_s(freq_hz: float, zeta: float) -> float:
    """``tau = 1 / (2 pi zeta f)``: the time the ring takes to fall by ``e`` (8.7 dB)."""
    return 1.0 / (2 * math.pi * zeta * freq_hz)


def ringdown_gap_s(
    m: VibrationMap,
    excitation: str,
    freq_hz: float,
    k: float,
    *,
    zeta: float = 0.0,
    fallback_zeta: float = 0.01,
    band_hz: float = 650.0,
) -> dict:
    """Silence to leave after a part at ``freq_hz`` on ``excitation``: ``k x tau``.

    ``zeta`` > 0 is used as given (at ``freq_hz``); 0: estimated from the map's half-power
    bandwidth at the nearest peak (its ``f_n``), else ``fallback_zeta``. Returns
    ``gap_s``, ``tau_s``, ``zeta``, ``freq_hz`` (the decaying mode's) and ``zeta_from``.
    """
    fn, z, src = float(freq_hz), float(zeta), "profile"
    if z <= 0:
        est = half_power_zeta(m, excitation, freq_hz, band_hz=band_hz)
        if est is not None:
            fn, z = est
            src = "map half-power bandwidth"
        else:
            z, src = float(fallback_zeta), "default (bandwidth not resolved)"
    tau = decay_time_s(fn, z)
    return {"gap_s": float(k * tau), "tau_s": tau, "zeta": z, "freq_hz": fn, "zeta_from": src}
