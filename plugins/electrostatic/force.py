"""Electrostatic attraction and friction change (paper Eqs. 1 and 2), detection threshold.

Eq. 1 (paper, after its ref. [18])::

    f_e(t) = eps0 V(t)^2 A / (2 (t_i + t_s) (t_i / eps_i + t_s / eps_s))

Eq. 2: F_f = mu (F_N + f_e), so the friction change is ``mu * f_e``.

The force goes with V^2: a sine of frequency f gives a mean force plus a component at
2 f; the time-averaged force uses V_rms^2. With eps_i == eps_s the formula reduces to the
parallel-plate force eps0 eps_r A V^2 / (2 d^2) (the test's independent reference).

Stratum corneum permittivity is strongly frequency dependent (FACTS, [recalled]). Model
used here (a constant-phase / power-law dielectric, the form skin impedance follows
between ~10 Hz and ~10 kHz): ``eps_s(f) = max(eps_min, eps_ref * (f / f_ref) ** -n)``
with f clamped to >= 1 Hz. The defaults (eps_ref 1000 at 100 Hz, n 0.2, eps_min 50) are
order-of-magnitude values recalled from skin impedance studies (Yamamoto & Yamamoto
1976): a profile overrides them. The leaky (conductive) behaviour of the skin that makes
electroadhesion fall at low frequency is outside Eq. 1 and not modelled.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

EPS0_F_PER_M = 8.8541878128e-12

#: Defaults of the [electrostatic] profile section (units in the names).
#: Sources: FACTS.md "Electrovibration" ([recalled] unless noted) and the paper.
DEFAULTS: dict[str, Any] = {
    "insulator_thickness_um": 1.0,  # FACTS: insulator ~1 um
    "insulator_eps_r": 4.0,  # FACTS: eps_r ~4
    "skin_thickness_um": 200.0,  # FACTS: stratum corneum 0.1-0.4 mm (fingertip)
    "skin_eps_r_ref": 1000.0,  # power-law model, value at skin_eps_ref_freq_hz
    "skin_eps_ref_freq_hz": 100.0,
    "skin_eps_exponent": 0.2,  # eps_s ~ f^-n
    "skin_eps_r_min": 50.0,  # high-frequency floor
    "contact_area_mm2": 100.0,  # one fingertip pad, ~1 cm^2
    "friction_coefficient": 0.5,  # finger on glass, 0.3-1
    "normal_force_n": 0.5,  # light exploration force
    # Detection threshold of sine stimuli (Vpp) vs frequency: U-shaped, minimum near
    # 80 Hz (FACTS [checked]), tens of volts (FACTS [recalled]); an illustrative curve
    # to be replaced by the lab's measured one.
    "threshold_freq_hz": [15.0, 30.0, 60.0, 80.0, 120.0, 180.0, 240.0, 480.0, 960.0, 1920.0],
    "threshold_vpp": [62.0, 44.0, 31.0, 27.0, 29.0, 33.0, 38.0, 55.0, 80.0, 115.0],
    # Square waves are detected below sines under ~60 Hz (FACTS [checked]).
    "threshold_square_vpp": [38.0, 31.0, 27.0, 26.0, 29.0, 33.0, 38.0, 55.0, 80.0, 115.0],
}


@dataclass(frozen=True)
class Material:
    """Finger/insulator properties for Eq. 1 (SI units)."""

    t_i_m: float
    eps_i: float
    t_s_m: float
    eps_s_ref: float
    eps_s_ref_freq_hz: float
    eps_s_exponent: float
    eps_s_min: float
    area_m2: float
    mu: float
    normal_force_n: float

    @classmethod
    def from_settings(cls, s: Mapping[str, Any] | None = None) -> Material:
        d = {**DEFAULTS, **(s or {})}
        return cls(
            t_i_m=d["insulator_thickness_um"] * 1e-6,
            eps_i=d["insulator_eps_r"],
            t_s_m=d["skin_thickness_um"] * 1e-6,
            eps_s_ref=d["skin_eps_r_ref"],
            eps_s_ref_freq_hz=d["skin_eps_ref_freq_hz"],
            eps_s_exponent=d["skin_eps_exponent"],
            eps_s_min=d["skin_eps_r_min"],
            area_m2=d["contact_area_mm2"] * 1e-6,
            mu=d["friction_coefficient"],
            normal_force_n=d["normal_force_n"],
        )


def skin_eps_r(freq_hz: float | np.ndarray, m: Material) -> np.ndarray:
    """Relative permittivity of the stratum corneum at ``freq_hz`` (power-law model)."""
    f = np.maximum(np.asarray(freq_hz, dtype=float), 1.0)
    eps = m.eps_s_ref * (f / m.eps_s_ref_freq_hz) ** (-m.eps_s_exponent)
    return np.maximum(eps, m.eps_s_min)


def force_per_v2(
    area_m2: float, t_i_m: float, eps_i: float, t_s_m: float, eps_s: float | np.ndarray
) -> np.ndarray:
    """Eq. 1 divided by V^2: newtons per volt squared."""
    eps_s = np.asarray(eps_s, dtype=float)
    return EPS0_F_PER_M * area_m2 / (2.0 * (t_i_m + t_s_m) * (t_i_m / eps_i + t_s_m / eps_s))


def attraction_force_n(v: np.ndarray | float, freq_hz: float, m: Material) -> np.ndarray:
    """Instantaneous attraction force (N) for voltage samples ``v`` (Eq. 1).

    ``freq_hz`` selects the skin permittivity (the dominant frequency of the stimulus).
    """
    k = force_per_v2(m.area_m2, m.t_i_m, m.eps_i, m.t_s_m, skin_eps_r(freq_hz, m))
    return k * np.square(np.asarray(v, dtype=float))


def friction_n(f_e_n: np.ndarray | float, m: Material) -> np.ndarray:
    """Eq. 2: friction force mu (F_N + f_e) in newtons."""
    return m.mu * (m.normal_force_n + np.asarray(f_e_n, dtype=float))


def rms_v(v: np.ndarray) -> float:
    a = np.asarray(v, dtype=float)
    return float(np.sqrt(np.mean(np.square(a)))) if a.size else 0.0


def dominant_freq_hz(v: np.ndarray, sample_rate_hz: float) -> float:
    """Frequency of the largest spectral line of ``v`` (0 for silence or DC)."""
    a = np.asarray(v, dtype=float)
    if a.size < 4 or not np.any(a):
        return 0.0
    spec = np.abs(np.fft.rfft((a - a.mean()) * np.hanning(a.size)))
    k = int(np.argmax(spec[1:]) + 1)
    return float(k * sample_rate_hz / a.size)


def expected_force(
    v: np.ndarray, sample_rate_hz: float, m: Material, freq_hz: float | None = None
) -> dict[str, float]:
    """What the console shows for a stimulus: mean and peak attraction, friction change.

    ``v`` in volts at the screen electrode. Mean force uses V_rms^2 (time average of
    Eq. 1); the peak uses max |V|.
    """
    a = np.asarray(v, dtype=float)
    f = dominant_freq_hz(a, sample_rate_hz) if freq_hz is None else float(freq_hz)
    k = float(force_per_v2(m.area_m2, m.t_i_m, m.eps_i, m.t_s_m, skin_eps_r(max(f, 1.0), m)))
    vr = rms_v(a)
    vp = float(np.max(np.abs(a))) if a.size else 0.0
    return {
        "freq_hz": f,
        "v_rms": vr,
        "v_peak": vp,
        "skin_eps_r": float(skin_eps_r(max(f, 1.0), m)),
        "force_mean_n": k * vr**2,
        "force_peak_n": k * vp**2,
        "friction_change_mean_n": m.mu * k * vr**2,
        "friction_change_peak_n": m.mu * k * vp**2,
        "friction_base_n": m.mu * m.normal_force_n,
    }


def threshold_vpp(
    freq_hz: float | np.ndarray,
    freqs_hz: Sequence[float],
    thresholds_vpp: Sequence[float],
) -> np.ndarray:
    """Detection threshold at ``freq_hz``: interpolated linearly in dB over log frequency.

    Outside the table the end values are held (never extrapolated).
    """
    fx = np.asarray(freqs_hz, dtype=float)
    ty = np.asarray(thresholds_vpp, dtype=float)
    if fx.size == 0 or fx.size != ty.size:
        raise ValueError(
            f"{ty.size} thresholds for {fx.size} frequencies; give one threshold per frequency"
        )
    if np.any(np.diff(fx) <= 0):
        raise ValueError("frequencies must increase strictly")
    if np.any(ty <= 0):
        raise ValueError("thresholds must be > 0")
    f = np.clip(np.asarray(freq_hz, dtype=float), fx[0], fx[-1])
    db = np.interp(np.log(f), np.log(fx), 20 * np.log10(ty))
    return 10 ** (db / 20)


def threshold_check(
    vpp: float, freq_hz: float, settings: Mapping[str, Any] | None = None, waveform: str = "sine"
) -> dict[str, Any]:
    """Whether a setting is felt: ``{"threshold_vpp", "margin_db", "below": bool}``."""
    d = {**DEFAULTS, **(settings or {})}
    key = "threshold_square_vpp" if waveform == "square" else "threshold_vpp"
    th = float(threshold_vpp(freq_hz, d["threshold_freq_hz"], d[key]))
    margin = 20 * np.log10(vpp / th) if vpp > 0 else float("-inf")
    return {"threshold_vpp": th, "margin_db": float(margin), "below": bool(vpp < th)}


def below_threshold(
    vpp: float, freq_hz: float, settings: Mapping[str, Any] | None = None, waveform: str = "sine"
) -> bool:
    """True when ``vpp`` at ``freq_hz`` is below the detection threshold (not felt)."""
    return threshold_check(vpp, freq_hz, settings, waveform)["below"]
