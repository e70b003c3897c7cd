"""Ring-down between flow parts: how long the plate keeps vibrating after a part stops.

After a tone near a mode at ``f_n`` with modal damping ``zeta`` stops, that mode decays
as ``exp(-t / tau)`` with ``tau = 1 / (2 pi zeta f_n)`` (0.3 s at 53 Hz, 1 %). Part 2's
passive point is part 1's active point, so with the relay gap alone (milliseconds) a
low-frequency part 1 still rings when part 2 starts. The ring-down-aware gap is
``k x tau`` of part 1's mode: after ``k`` decay times the ring is ``8.7 k`` dB down
(part 1 at ``SL`` dB above threshold falls below it for ``k >= SL / 8.7``).

``zeta`` comes from the map's half-power bandwidth at the peak nearest the frequency
(``2 zeta f_n = f_2 - f_1`` where the spatial RMS of ``|H|`` is ``peak / sqrt 2``),
or from a given value when the bandwidth is not resolved.
"""

from __future__ import annotations

import math

import numpy as np

from console.vibration_map import VibrationMap


def half_power_zeta(
    m: VibrationMap, excitation: str, freq_hz: float, *, band_hz: float = 650.0
) -> tuple[float, float] | None:
    """``(f_n, zeta)`` of the resonance nearest ``freq_hz`` in the spatial RMS of the
    excitation's ``|H|``, from its half-power bandwidth; ``None`` when no peak is found
    or its bandwidth spans fewer than 3 bins (not resolved: too coarse to trust)."""
    from plugins.vibrotactile.tables import usable_bins

    keep = usable_bins(m, max(band_hz, float(freq_hz)))
    f = m.freq_hz[keep]
    e = m.excitation_index(excitation)
    r = np.sqrt(np.mean(np.abs(m.frf_um_per_v[e][:, keep]) ** 2, axis=0))
    if r.size < 3:
        return None
    peaks = np.flatnonzero((r[1:-1] > r[:-2]) & (r[1:-1] >= r[2:])) + 1
    if peaks.size == 0:
        return None
    k = int(peaks[np.argmin(np.abs(f[peaks] - freq_hz))])
    half = r[k] / math.sqrt(2)
    sides = []
    for step in (-1, 1):
        j = k
        while 0 <= j + step < r.size and r[j + step] >= half:
            j += step
            if r[j] > r[k]:  # climbed into a stronger neighbouring mode
                j = -1
                break
        if j < 0 or not 0 <= j + step < r.size:
            sides.append(None)
            continue
        # linear interpolation of the crossing between bins j and j + step
        t = (r[j] - half) / max(r[j] - r[j + step], 1e-300)
        sides.append(float(f[j] + t * (f[j + step] - f[j])))
    lo, hi = sides
    if lo is None and hi is None:
        return None
    fn = float(f[k])
    bw = (hi - lo) if lo is not None and hi is not None else 2 * abs((hi or lo) - fn)
    df = float(np.median(np.diff(f)))
    if bw < 3 * df:
        return None
    return fn, bw / (2 * fn)


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
