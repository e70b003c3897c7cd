"""The roving sensor's mass taken out of a map: an analytic single mode and the plate twin.

References, independent of the correction: a one-mode oscillator with the point mass in
its equation of motion, and the plate twin's modes solved again with the mass in the mass
matrix (``with_point_mass``) against the twin without it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from console.plugin_api import UserError
from plugins.vibrotactile.mass_correction import (
    correct_map,
    factor,
    fit_correction,
    fit_correction_of,
    unload,
)

F_HZ, ZETA = 100.0, 0.01


def _one_mode(freq_hz, phi_i, phi_j, eps):
    """Receptance of one mode; with the mass its equation of motion reads
    (w_r^2 - (1 + m phi_j^2) w^2 + 2 i zeta w_r w) q = phi_i F."""
    w, wr = 2 * math.pi * freq_hz, 2 * math.pi * F_HZ
    return phi_i * phi_j / (wr**2 - (1 + eps) * w**2 + 2j * ZETA * wr * w)


def _pole(f_hz):
    w = 2 * math.pi * f_hz
    return complex(-ZETA * w, w * math.sqrt(1 - ZETA**2))


def _db(a, b):
    return np.abs(20 * np.log10(np.abs(a) / np.abs(b)))


def test_one_mode_the_correction_is_exact_and_its_mass_ratios_are_found():
    f = np.arange(60.0, 140.0, 0.25)
    phi_j = np.array([0.3, 0.7, 1.0, 0.5])
    eps = 0.012 * phi_j**2  # m phi_j^2: the mode drops 0.6 % with the sensor on its antinode
    true = np.stack([_one_mode(f, 1.0, p, 0.0) for p in phi_j])[None]  # (1, P, F)
    loaded = np.stack([_one_mode(f, 1.0, p, e) for p, e in zip(phi_j, eps, strict=True)])[None]
    assert _db(loaded, true).max() > 2.0  # what the mass does near the peak
    # exact with the true mass ratios: H = H^m (1 - m w^2 H_jj)
    for j in range(phi_j.size):
        got = unload(loaded[:, j], f, eps[j : j + 1], np.array([_pole(F_HZ)]))
        assert np.allclose(got, true[:, j], rtol=1e-9)
    # and from the loaded map alone: the poles' shifts against the shape give eps
    corr = fit_correction(f, loaded, (60.0, 140.0), poles=np.array([_pole(99.7)]))
    assert corr.uncorrected == []
    assert np.allclose(corr.eps[0], eps, rtol=0.03)
    assert abs(abs(corr.poles[0]) / (2 * math.pi) - F_HZ) < 0.01
    fixed = np.stack([unload(loaded[:, j], f, corr.eps[:, j], corr.poles) for j in range(4)], 1)
    assert _db(fixed, true).max() < 0.1


def test_one_point_alone_cannot_tell_the_mass_and_is_left_as_measured():
    f = np.arange(60.0, 140.0, 0.25)
    loaded = _one_mode(f, 1.0, 1.0, 0.012)[None, None]
    corr = fit_correction(f, loaded, (60.0, 140.0), poles=np.array([_pole(99.4)]))
    assert corr.uncorrected == [0] and not corr.eps.any()
    assert np.allclose(factor(f, corr.eps[:, 0], corr.poles), 1.0)


def test_a_3_point_twin_map_with_the_sensor_mass_comes_within_1_db():
    from console.plugin_api import make_map
    from plugins.twin.plate.model import build_twin, default_params
    from plugins.twin.plate.sensor import with_point_mass

    twin = build_twin(default_params())
    f = np.arange(20.0, 625.0, 1 / 2.25)  # the roving run's bins (1.5 s chirp + 0.75 s tail)
    pts = np.array([[41.73, 43.645], [341.73, 223.645], [701.73, 403.645]])
    true = twin.frf_um_per_v(pts[:, 0], pts[:, 1], f)
    loaded = np.stack(
        [with_point_mass(twin, x, y, 0.007).frf_um_per_v([x], [y], f)[:, 0] for x, y in pts], 1
    )
    m = make_map(loaded, f, np.array([1, 42, 84]), pts, ("PA", "PB", "PC", "PD", "PALL"))
    corr = fit_correction_of(m, order=60)
    fixed, _ = correct_map(m, 7.0, corr=corr)
    low = f < 400
    before, after = (
        _db(loaded[..., low], true[..., low]),
        _db(fixed.frf_um_per_v[..., low], true[..., low]),
    )
    assert before.max() > 2.0 and np.mean(before <= 1.0) < 0.96
    assert np.mean(after <= 1.0) > 0.995 and np.percentile(after, 95) < 0.6
    assert np.median(after) < np.median(before)
    # over the whole band it is better, not worse (the band's top: see the report)
    assert np.median(_db(fixed.frf_um_per_v, true)) < np.median(_db(loaded, true))


def test_a_bad_sensor_mass_is_one_line():
    with pytest.raises(UserError) as e:
        correct_map(None, 0.0)
    assert "--sensor-mass-g 0" in str(e.value) and "\n" not in str(e.value)
