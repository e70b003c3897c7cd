"""Two-finger rotation tracking: noise, swaps, lifts, wrap-around, filter accuracy."""

import numpy as np
import pytest

from plugins.electrostatic.rotation import RotationTracker, alpha_beta_noise_ratio, track, wrap_deg
from plugins.electrostatic.simulate import min_jerk, rotation_frames

FPS = 60.0


def _angles(states):
    return np.array([s.angle_deg for s in states])


def test_wrap_deg():
    assert wrap_deg(190.0) == pytest.approx(-170.0)
    assert wrap_deg(-180.0) == pytest.approx(180.0)
    assert wrap_deg(100.0, 180.0) == pytest.approx(-80.0)


def test_clean_rotation_is_followed_with_its_velocity():
    t = np.arange(0, 2, 1 / FPS)
    true = min_jerk(t, 0.2, 1.5, 0.0, 120.0)
    st = track(rotation_frames(true, t, noise_mm=0.0, pivot_drift_mm=0.0))
    assert np.max(np.abs(_angles(st) - true)) < 2.0
    vel_true = np.gradient(true, t)
    v = np.array([s.velocity_deg_s for s in st])
    assert np.max(np.abs(v - vel_true)[10:]) < 25.0  # peak ~150 deg/s
    assert abs(v[-1]) < 1.0


def test_constant_velocity_has_no_steady_state_lag():
    t = np.arange(0, 2, 1 / FPS)
    true = 90.0 * t  # 90 deg/s
    st = track(rotation_frames(true, t, noise_mm=0.0, pivot_drift_mm=0.0))
    assert _angles(st)[-1] == pytest.approx(true[-1], abs=0.05)
    assert st[-1].velocity_deg_s == pytest.approx(90.0, abs=0.5)


def test_filter_noise_matches_the_alpha_beta_formula():
    # independent reference: Kalata's steady-state variance ratio of the alpha-beta filter
    rng = np.random.default_rng(3)
    n, sigma_deg = 20000, 1.0
    tr = RotationTracker(alpha=0.5, beta=0.15)
    r = 100.0
    est = []
    for i in range(n):
        a = np.radians(rng.normal(0.0, sigma_deg))
        tr.update(i / FPS, [(0.0, 0.0), (r * np.cos(a), r * np.sin(a))])
        est.append((tr.angle_deg, tr.velocity_deg_s))
    est = np.array(est[200:])
    px, pv = alpha_beta_noise_ratio(0.5, 0.15)
    assert np.std(est[:, 0]) == pytest.approx(px * sigma_deg, rel=0.08)
    assert np.std(est[:, 1]) == pytest.approx(pv * sigma_deg * FPS, rel=0.08)
    assert px < 0.7  # the filter actually removes noise


def test_wrap_around_past_180_is_unwrapped():
    t = np.arange(0, 3, 1 / FPS)
    true = min_jerk(t, 0.1, 2.5, 0.0, 400.0)
    fr = rotation_frames(true, t, base_deg=170.0, noise_mm=0.2, rng=np.random.default_rng(1))
    a = _angles(track(fr))
    assert a[-1] == pytest.approx(400.0, abs=1.5)
    assert np.max(np.abs(np.diff(a))) < 8.0  # no 360 jump


def test_identity_swaps_change_nothing():
    t = np.arange(0, 2, 1 / FPS)
    true = min_jerk(t, 0.1, 1.5, 0.0, -200.0)
    kw = dict(noise_mm=0.3, rng=None)
    a = _angles(track(rotation_frames(true, t, **{**kw, "rng": np.random.default_rng(5)})))
    b = _angles(
        track(
            rotation_frames(
                true, t, swap_frames=[20, 21, 50, 77], **{**kw, "rng": np.random.default_rng(5)}
            )
        )
    )
    np.testing.assert_allclose(a, b, atol=1e-9)


@pytest.mark.parametrize("which", ["index", "thumb", "both"])
@pytest.mark.parametrize("n_lift", [1, 2])
def test_a_finger_lifting_for_a_frame_or_two_is_bridged(which, n_lift):
    t = np.arange(0, 2, 1 / FPS)
    true = 100.0 * t  # steady turn: prediction is exact, a hold would lag
    fr = rotation_frames(
        true, t, noise_mm=0.0, pivot_drift_mm=0.0, lift_frames=[(60, which, n_lift)]
    )
    st = track(fr)
    assert all(s.touching for s in st)
    err = np.abs(_angles(st) - true)
    assert err[55:80].max() < 1.0
    assert not st[60].measured or which == "thumb"


def test_a_long_lift_releases_and_regrip_continues_without_a_jump():
    t = np.arange(0, 3, 1 / FPS)
    true = np.where(t < 1.0, 90.0 * t, 90.0 + 60.0 * (t - 1.5).clip(0))
    hand = true.copy()
    hand[t >= 1.5] -= 120.0  # the hand comes back turned by -120 deg when it touches again
    fr = rotation_frames(hand, t, noise_mm=0.0, pivot_drift_mm=0.0, lift_frames=[(60, "both", 30)])
    st = track(fr, max_hold_frames=3)
    assert not st[70].touching and st[70].velocity_deg_s == 0.0
    a = _angles(st)
    assert np.max(np.abs(np.diff(a))) < 3.0
    assert a[-1] == pytest.approx(true[-1], abs=4.0)


def test_stray_third_contact_and_bad_points_are_ignored():
    t = np.arange(0, 1.5, 1 / FPS)
    true = min_jerk(t, 0.1, 1.0, 0.0, 90.0)
    fr = rotation_frames(true, t, noise_mm=0.0, extra_contact_frames=list(range(0, 90, 3)))
    fr[40] = (fr[40][0], (*fr[40][1], (float("nan"), 3.0)))
    a = _angles(track(fr))
    assert np.all(np.isfinite(a))
    assert np.max(np.abs(a - true)) < 2.5


def test_no_contacts_means_no_grip():
    tr = RotationTracker(start_angle_deg=33.0)
    s = tr.update(0.0, [])
    assert not s.touching and s.angle_deg == 33.0
    s = tr.update(0.1, [(0.0, 0.0)])
    assert not s.touching
    with pytest.raises(ValueError):
        RotationTracker(alpha=1.0, beta=2.5)
