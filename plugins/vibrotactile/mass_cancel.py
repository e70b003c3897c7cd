"""The roving sensor's mass cancelled exactly with a clip-on dummy of known mass.

A point mass m at the sensor point j turns the mass-free receptance H_ij into

    H^m_ij = H_ij / (1 - m w^2 H_jj),   so   1 / H^m_ij = 1 / H_ij - m w^2 H_jj / H_ij,

linear in m for every excitation i (PALL too: a sum over patches at the same j). Measured
at each point twice, with the sensor alone (m_s, FRF H1) and with the sensor and a dummy of
m_d clipped on it (m_s + m_d, FRF H2), the line through the two gives its value at m = 0:

    1 / H = (1 + r) / H1 - r / H2,   r = m_s / m_d,   i.e.  H = H1 H2 / ((1 + r) H2 - r H1)

(``r = 1``: 1 / H = 2 / H1 - 1 / H2, the classic mass cancellation of experimental modal
analysis). Nothing is fitted: no poles, no mode shapes, exact for a point mass (the sensor
and the dummy move with the plate; their rotary inertia is neglected). The price is a
second pass and noise: with relative errors e1, e2 on H1, H2 where the mass hardly matters,
the result's error is (1 + r) e1 - r e2, a standard deviation sqrt((1 + r)^2 + r^2) times
one measurement's (2.2 x for r = 1, 1.6 x for r = 1/2): a dummy heavier than the sensor
costs less noise. Both passes must be measured the same way (bins, delay removed).
"""

from __future__ import annotations

import math

import numpy as np

from console.plugin_api import UserError


def check_masses(sensor_mass_g: float | None, dummy_mass_g: float) -> float:
    """r = m_s / m_d, or one line naming the option to fix."""
    if not 0 < dummy_mass_g <= 500:
        raise UserError(f"--dummy-mass-g {dummy_mass_g:g}: give the dummy's mass, 0-500 g")
    if sensor_mass_g is None or not 0 < sensor_mass_g <= 500:
        raise UserError(
            "--dummy-mass-g needs --sensor-mass-g (the sensor's own mass, e.g. 7): the "
            "cancellation extrapolates the two passes to zero mass"
        )
    return sensor_mass_g / dummy_mass_g


def noise_gain(sensor_mass_g: float, dummy_mass_g: float) -> float:
    """How much the cancellation multiplies a pass's random error where the mass does not
    matter: sqrt((1 + r)^2 + r^2)."""
    r = sensor_mass_g / dummy_mass_g
    return math.sqrt((1 + r) ** 2 + r**2)


def cancel(
    frf_sensor: np.ndarray, frf_with_dummy: np.ndarray, sensor_mass_g: float, dummy_mass_g: float
) -> np.ndarray:
    """The mass-free FRF from the two passes (any shape, complex, the same units).

    Bins where either pass is 0 (masked) stay 0; where the two passes make the line's
    value at zero mass infinite (noise on both at an antiresonance) the sensor pass is kept."""
    r = check_masses(sensor_mass_g, dummy_mass_g)
    h1 = np.asarray(frf_sensor, complex)
    h2 = np.asarray(frf_with_dummy, complex)
    den = (1 + r) * h2 - r * h1
    with np.errstate(divide="ignore", invalid="ignore"):
        h = h1 * h2 / den
    ok = np.isfinite(h) & (np.abs(den) > 0)
    h = np.where(ok, h, h1)
    return np.where((h1 == 0) | (h2 == 0), 0.0, h)


def cancel_coherence(
    coh_sensor: np.ndarray,
    coh_with_dummy: np.ndarray,
    frf_sensor: np.ndarray | None = None,
    frf_with_dummy: np.ndarray | None = None,
    sensor_mass_g: float | None = None,
    dummy_mass_g: float | None = None,
) -> np.ndarray:
    """The result's coherence, its noise propagated from the two passes'.

    Each pass's noise-to-signal ratio is (1 - g^2) / g^2; to first order H's relative
    error is (1 + r) (H / H1) e1 - r (H / H2) e2, so its ratio is
    (1 + r)^2 |H / H1|^2 q1 + r^2 |H / H2|^2 q2, and the coherence 1 / (1 + q). Near an
    antiresonance, where the line's value at zero mass divides two small numbers, H / H1
    is large and the result is (rightly) not coherent. Without the FRFs and masses: the
    worse of the two passes', bin by bin (a lower bound on the noise)."""
    c1 = np.clip(np.asarray(coh_sensor, float), 1e-12, 1.0)
    c2 = np.clip(np.asarray(coh_with_dummy, float), 1e-12, 1.0)
    if frf_sensor is None or frf_with_dummy is None or not sensor_mass_g or not dummy_mass_g:
        return np.minimum(np.asarray(coh_sensor), np.asarray(coh_with_dummy))
    r = check_masses(sensor_mass_g, dummy_mass_g)
    h1 = np.asarray(frf_sensor, complex)
    h2 = np.asarray(frf_with_dummy, complex)
    h = cancel(h1, h2, sensor_mass_g, dummy_mass_g)
    with np.errstate(divide="ignore", invalid="ignore"):
        q = (1 + r) ** 2 * np.abs(h / h1) ** 2 * (1 - c1) / c1
        q = q + r**2 * np.abs(h / h2) ** 2 * (1 - c2) / c2
        coh = 1.0 / (1.0 + q)
    return np.where(np.isfinite(coh), coh, 0.0)
