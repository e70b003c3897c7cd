"""Touch calibration: homography + residual RBF, against known mappings."""

import math

import cv2
import numpy as np
import pytest

from console.core.errors import UserError
from console.core.types import Contact
from plugins.gestures.calibration import (
    Calibration,
    CalibrationSession,
    apply_homography,
    calibrate,
    target_grid,
)

CORNERS_PX = np.float32([[627, 429], [13, 421], [21, 52], [617, 57]])
TABLE = (743.46, 447.29)


def truth(k1=0.0):
    """mm -> px: a mirrored keystone homography plus optional radial distortion."""
    src = np.float32([[0, 0], [TABLE[0], 0], [TABLE[0], TABLE[1]], [0, TABLE[1]]])
    h = cv2.getPerspectiveTransform(src, CORNERS_PX).astype(np.float64)

    def mm_to_px(mm):
        p = apply_homography(h, mm)
        c = np.array([319.5, 239.5])
        d = (p - c) / 540.0
        r2 = np.sum(d * d, axis=1, keepdims=True)
        return c + 540.0 * d * (1 + k1 * r2)

    return mm_to_px


def held_out_error(cal, mm_to_px):
    g = target_grid(TABLE, 15, 9, 60.0)
    return np.hypot(*(cal.px_to_mm(mm_to_px(g)) - g).T)


def test_exact_homography_is_recovered_and_matches_a_numpy_dlt():
    f = truth()
    mm = target_grid(TABLE, 5, 4)
    cal = calibrate(f(mm), mm)
    assert cal.rms_mm < 1e-6 and cal.outliers == []
    assert held_out_error(cal, f).max() < 1e-6
    # second method: direct linear transform by SVD
    px = f(mm)
    rows = []
    for (x, y), (u, v) in zip(px, mm, strict=True):
        rows.append([x, y, 1, 0, 0, 0, -u * x, -u * y, -u])
        rows.append([0, 0, 0, x, y, 1, -v * x, -v * y, -v])
    h = np.linalg.svd(np.array(rows))[2][-1].reshape(3, 3)
    q = np.array([[50.0, 60.0], [320.0, 240.0], [600.0, 420.0]])
    np.testing.assert_allclose(cal.px_to_mm(q), apply_homography(h, q), atol=1e-4)


def test_residual_correction_removes_lens_distortion():
    f = truth(k1=-0.2)  # barrel, like a wide webcam lens
    mm = target_grid(TABLE, 7, 5)
    plain = calibrate(f(mm), mm, correction=False)
    full = calibrate(f(mm), mm)
    assert full.smoothing is not None
    e_plain, e_full = held_out_error(plain, f), held_out_error(full, f)
    assert e_plain.max() > 4.0  # the distortion is visible without correction
    assert e_full.max() < 0.3 * e_plain.max()
    assert full.loo_rms_mm < full.loo_rms_homography_mm


def test_an_outlier_touch_is_rejected_and_noise_is_not_overfitted():
    rng = np.random.default_rng(3)
    f = truth(k1=-0.08)
    mm = target_grid(TABLE, 7, 5)
    px = f(mm + rng.normal(0, 1.5, mm.shape))  # touch error ~1.5 mm
    px[11] += (60.0, -45.0)  # one touch far from its target
    cal = calibrate(px, mm)
    assert cal.outliers == [11]
    assert np.sqrt(np.mean(held_out_error(cal, f) ** 2)) < 3.0
    assert cal.max_mm < 8.0


def test_save_and_load_round_trip(tmp_path):
    f = truth(k1=-0.1)
    mm = target_grid(TABLE, 6, 4)
    cal = calibrate(f(mm), mm)
    p = cal.save(tmp_path / "touch_calibration.json")
    back = Calibration.load(p)
    q = np.array([[100.0, 100.0], [320.0, 240.0], [600.0, 400.0]])
    np.testing.assert_allclose(back.px_to_mm(q), cal.px_to_mm(q), atol=1e-9)
    assert back.report() == cal.report()
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(UserError, match="bad.json"):
        Calibration.load(tmp_path / "bad.json")
    with pytest.raises(UserError, match="run the touch calibration"):
        Calibration.load(tmp_path / "missing.json")


def test_bad_inputs_are_user_errors():
    with pytest.raises(UserError, match="at least 4"):
        calibrate([[0, 0], [1, 1]], [[0, 0], [1, 1]])
    with pytest.raises(UserError, match="targets"):
        calibrate(np.zeros((5, 2)), np.zeros((4, 2)))
    line = np.column_stack([np.arange(6.0), np.arange(6.0)])
    with pytest.raises(UserError):
        calibrate(line * 50, line * 40)


def test_session_walks_the_targets_from_contacts():
    f = truth()
    mm = target_grid(TABLE, 3, 3)
    s = CalibrationSession(mm, hold_frames=5, lift_frames=2)
    events = []
    rng = np.random.default_rng(0)
    while (t := s.next_target()) is not None:
        i, target = t
        p = f(np.array([target]))[0]
        events.append(s.feed([]))
        events.append(s.feed([Contact(0, (1.0, 1.0)), Contact(1, (5.0, 5.0))]))
        for _ in range(5):
            events.append(s.feed([Contact(0, tuple(p + rng.normal(0, 0.3, 2)))]))
        events.append(s.feed([]))
        events.append(s.feed([]))
    assert "ambiguous" in events and events.count("recorded") == 9
    assert events[-1] == "done" and s.progress() == (9, 9)
    cal = s.finish()
    assert cal.rms_mm < 1.0


def test_session_skip_redo_and_too_few():
    s = CalibrationSession(target_grid(TABLE, 2, 2), hold_frames=1, lift_frames=1)
    s.record((10.0, 10.0))
    s.feed([])
    s.skip()
    assert s.next_target()[0] == 2
    s.redo(0)
    assert s.next_target()[0] == 0 and s.touches_px[0] is None
    with pytest.raises(UserError, match="at least 4"):
        s.finish()
    assert math.isfinite(s.hold_frames)
