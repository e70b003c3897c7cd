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


def cancel_coherence(coh_sensor: np.ndarray, coh_with_dummy: np.ndarray) -> np.ndarray:
    """The result's coherence: the worse of the two passes', bin by bin."""
    return np.minimum(np.asarray(coh_sensor), np.asarray(coh_with_dummy))
