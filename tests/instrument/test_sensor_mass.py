"""The roving sensor's mass on the plate twin: modes shift as the Rayleigh quotient says."""

from __future__ import annotations

import numpy as np
from scipy import linalg

from plugins.twin.plate.model import build_twin, default_params
from plugins.twin.plate.sensor import accel_frf, rayleigh_freq_hz, with_point_mass


def test_a_7_g_sensor_shifts_the_modes_as_the_rayleigh_quotient_says():
    twin = build_twin(default_params())
    x_mm, y_mm = 371.73, 223.645  # the middle of the glass: antinode of the first mode
    loaded = with_point_mass(twin, x_mm, y_mm, 0.007)
    ref = rayleigh_freq_hz(twin, x_mm, y_mm, 0.007)  # first order, independent of the solve
    n = 8
    shift = twin.freq_hz[:n] - loaded.freq_hz[:n]
    shift_ref = twin.freq_hz[:n] - ref[:n]
    assert shift[0] > 0.2  # a quarter of the first mode's half-power width (2 zeta f ~ 1 Hz)
    assert np.all(shift >= -1e-6)  # a mass never raises a mode
    # Rayleigh's quotient with the unloaded shape is an upper bound of each loaded mode:
    # the solve shifts at least as much, and within 10 % of it (close modes couple)
    assert np.all(shift >= shift_ref - 2e-3)
    assert np.allclose(shift, shift_ref, rtol=0.10, atol=2e-3)
    # the whole Ritz basis with the mass matrix M + m v v^T, solved directly
    sysm = twin.modes.system
    xi, eta = 2 * x_mm / 1e3 / sysm.plate.a_m - 1, 2 * y_mm / 1e3 / sysm.plate.b_m - 1
    v = np.outer(sysm.bx.values(np.array([xi]))[0], sysm.by.values(np.array([eta]))[0]).ravel()
    w2 = linalg.eigh(
        sysm.k, sysm.m_scale * np.eye(v.size) + 0.007 * np.outer(v, v), eigvals_only=True
    )
    full_hz = np.sqrt(w2[:n]) / (2 * np.pi)
    assert np.allclose(loaded.freq_hz[:n], full_hz, atol=0.02)


def test_a_sensor_on_a_nodal_line_leaves_that_mode_alone():
    twin = build_twin(default_params())
    x_mm, y_mm = 371.73, 223.645
    phi = twin.modes.shapes(np.array([x_mm / 1e3]), np.array([y_mm / 1e3]))[0]
    node = int(np.argmin(np.abs(phi[:6]) / np.abs(phi[:6]).max()))
    loaded = with_point_mass(twin, x_mm, y_mm, 0.010)
    assert abs(loaded.freq_hz[node] - twin.freq_hz[node]) < 1e-3
    # the acceleration FRF is the displacement FRF x -(2 pi f)^2
    f = np.array([80.0, 310.0])
    disp = twin.frf_um_per_v([x_mm], [y_mm], f, ("PA", "PB", "PC", "PD"))[:, 0] / 1e6
    assert np.allclose(accel_frf(twin, x_mm, y_mm, f), -((2 * np.pi * f) ** 2) * disp)
