"""Fourier descriptors: analytic ellipse, invariances, sign ambiguity, pyefd cross-check."""

import math

import numpy as np
import pyefd
import pytest

from plugins.gestures.descriptors import (
    fourier_coefficients,
    fourier_descriptors,
    resample_contour,
)


def ellipse(a, b, n=400, start=0.0):
    t = start + np.arange(n) * 2 * math.pi / n
    return np.column_stack([a * np.cos(t), b * np.sin(t)])


def hand_like(n=720):
    """A smooth, asymmetric star (no symmetry that would hide a sign error)."""
    t = np.arange(n) * 2 * math.pi / n
    r = 50 + 12 * np.cos(3 * t) + 7 * np.sin(5 * t + 0.4) + 5 * np.cos(2 * t + 1.0)
    return np.column_stack([r * np.cos(t), r * np.sin(t)])


def transform(p, angle_deg=0.0, scale=1.0, shift=(0.0, 0.0), start=0, reverse=False):
    a = math.radians(angle_deg)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    q = scale * p @ rot.T + np.asarray(shift)
    q = np.roll(q, -start, axis=0)
    return q[::-1] if reverse else q


def test_square_matches_the_analytic_series():
    """A regular N-gon traversed at constant speed has Z_k only for k = 1 + mN, with
    |Z_k| / |Z_1| = 1 / k^2 (z'' is N equal, rotated deltas)."""
    sq = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
    z = fourier_coefficients(sq, 1024)
    mags = np.abs(z) / abs(z[1])
    for k in (-3, 5, -7, 9):
        assert mags[k] == pytest.approx(1 / k**2, rel=1e-3)
    for k in (2, -2, 3, 4, -5, 6):
        assert mags[k] < 1e-6
    d = fourier_descriptors(sq, 6, n_samples=1024)
    ks = [-6, -5, -4, -3, -2, -1, 2, 3, 4, 5, 6]
    mag_block = d[2 * len(ks) :]
    assert mag_block[ks.index(-3)] == pytest.approx(1 / 9, rel=1e-3)
    assert mag_block[ks.index(5)] == pytest.approx(1 / 25, rel=1e-3)


def test_circle_has_only_the_first_harmonic():
    t = np.arange(500) * 2 * math.pi / 500
    z = fourier_coefficients(np.column_stack([7 * np.cos(t), 7 * np.sin(t)]), 256)
    assert abs(z[1]) == pytest.approx(7.0, rel=1e-4)
    assert np.delete(np.abs(z), [0, 1]).max() < 1e-3


@pytest.mark.parametrize("angle", [0.0, 37.0, 90.0, 180.0, -135.0])
@pytest.mark.parametrize("start", [0, 91, 360])
def test_invariant_to_translation_scale_rotation_start_and_direction(angle, start):
    base = fourier_descriptors(hand_like(), 12)
    moved = transform(hand_like(), angle, 2.7, (300.0, -40.0), start, reverse=start == 91)
    d = fourier_descriptors(moved, 12)
    assert np.all(np.isfinite(d))
    np.testing.assert_allclose(d, base, atol=2e-3)


def test_exact_180_degree_rotation_and_half_contour_start_shift_give_same_signs():
    p = hand_like()
    base = fourier_descriptors(p, 10)
    for q in (
        transform(p, 180.0),
        transform(p, 0, start=len(p) // 2),
        transform(p, 180.0, start=len(p) // 2),
    ):
        np.testing.assert_allclose(fourier_descriptors(q, 10), base, atol=2e-3)


def test_orientation_kept_when_not_rotation_invariant():
    p = hand_like()
    a = fourier_descriptors(p, 8, rotation_invariant=False)
    b = fourier_descriptors(transform(p, 0, start=200), 8, rotation_invariant=False)
    c = fourier_descriptors(transform(p, 90.0), 8, rotation_invariant=False)
    np.testing.assert_allclose(a, b, atol=2e-3)
    assert np.abs(a - c).max() > 0.05


def test_different_shapes_differ():
    assert (
        np.abs(fourier_descriptors(hand_like(), 8) - fourier_descriptors(ellipse(80, 30), 8)).max()
        > 0.05
    )


def test_duplicate_points_and_degenerate_contours_give_no_nan():
    p = hand_like(120)
    dup = np.repeat(p, 3, axis=0)  # every point three times
    d = fourier_descriptors(dup, 8)
    assert np.all(np.isfinite(d))
    np.testing.assert_allclose(d, fourier_descriptors(p, 8), atol=1e-9)
    for bad in (np.zeros((5, 2)), np.array([[1.0, 2.0]]), np.array([[0, 0], [10, 0], [0, 0]])):
        assert np.all(np.isfinite(fourier_descriptors(bad, 8)))
    with pytest.raises(ValueError):
        resample_contour(np.zeros((0, 2)), 8)


def test_agrees_with_pyefd_elliptic_coefficients():
    """Second method: pyefd integrates the polygon exactly; its elliptic coefficients map
    to ours as Z_n = ((a+d) + i(c-b))/2 and Z_-n = ((a-d) + i(c+b))/2."""
    p = hand_like(360)
    ours = fourier_coefficients(p, 1024)
    efd = pyefd.elliptic_fourier_descriptors(p, order=8, normalize=False)
    for n in range(1, 9):
        a, b, c, d = efd[n - 1]
        zp = complex(a + d, c - b) / 2
        zm = complex(a - d, c + b) / 2
        assert abs(ours[n]) == pytest.approx(abs(zp), rel=2e-2, abs=1e-2)
        assert abs(ours[-n]) == pytest.approx(abs(zm), rel=2e-2, abs=1e-2)
