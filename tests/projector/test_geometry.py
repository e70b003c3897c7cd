"""Projector calibration: table mm -> projector px homography, checked against OpenCV."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from console.core.errors import UserError
from plugins.projector.geometry import (
    GLASS_MM,
    Calibration,
    apply,
    default_calibration,
    fit_homography,
    glass_corners_mm,
    load_calibration,
    save_calibration,
)


def keystone_quad(frame=(1280, 800)):
    """Glass corners as a slightly keystoned, rotated quad inside the frame."""
    return np.array([[40.0, 22.0], [1250.0, 61.0], [1203.0, 770.0], [71.0, 741.0]])


def test_default_maps_glass_corners_onto_frame_corners():
    cal = default_calibration((1920, 1080))
    px = cal.to_px(glass_corners_mm())
    assert np.allclose(px, [[0, 0], [1920, 0], [1920, 1080], [0, 1080]], atol=1e-6)
    assert np.allclose(cal.to_px([[GLASS_MM[0] / 2, GLASS_MM[1] / 2]]), [[960, 540]], atol=1e-6)


def test_four_points_match_opencv_perspective_transform():
    src = glass_corners_mm().astype(np.float32)
    dst = keystone_quad().astype(np.float32)
    ref = cv2.getPerspectiveTransform(src, dst)
    h = fit_homography(src, dst)
    pts = np.random.default_rng(1).uniform([0, 0], GLASS_MM, size=(50, 2))
    assert np.allclose(apply(h, pts), apply(ref, pts), atol=1e-3)


def test_many_noisy_points_match_opencv_least_squares():
    rng = np.random.default_rng(2)
    h0 = cv2.getPerspectiveTransform(
        glass_corners_mm().astype(np.float32), keystone_quad().astype(np.float32)
    )
    src = rng.uniform([0, 0], GLASS_MM, size=(60, 2))
    dst = apply(h0, src) + rng.normal(0, 0.5, size=(60, 2))
    ours = fit_homography(src, dst)
    ref, _ = cv2.findHomography(src, dst, 0)
    probe = rng.uniform([0, 0], GLASS_MM, size=(40, 2))
    # both minimise the algebraic error; they agree to well under a pixel
    assert np.abs(apply(ours, probe) - apply(ref, probe)).max() < 0.2
    assert np.abs(apply(ours, probe) - apply(h0, probe)).max() < 1.0


@pytest.mark.parametrize(
    "src",
    [
        [[0, 0], [100, 0], [200, 0], [0, 100]],  # three on a line
        [[0, 0], [100, 100], [200, 200], [300, 300]],  # all on a line
        [[0, 0], [0, 0], [100, 0], [0, 100]],  # a repeated point
    ],
)
def test_degenerate_points_are_refused(src):
    with pytest.raises(UserError, match="degenerate"):
        fit_homography(np.array(src, float), np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float))


def test_too_few_points_are_refused():
    with pytest.raises(UserError, match="at least 4"):
        fit_homography(np.zeros((3, 2)), np.zeros((3, 2)))


def test_swapped_corners_fold_the_glass_and_are_refused():
    quad = keystone_quad()[[0, 2, 1, 3]]  # corners 2 and 3 swapped: a bow tie
    with pytest.raises(UserError, match="folded"):
        Calibration((1280, 800), [tuple(p) for p in glass_corners_mm()], [tuple(p) for p in quad])


def test_mirrored_projection_is_allowed_and_keeps_w_positive():
    # rear projection through a mirror flips the image: a valid calibration
    quad = np.array([[1280.0, 0], [0, 0], [0, 800], [1280, 800]])
    cal = Calibration((1280, 800), [tuple(p) for p in glass_corners_mm()], [tuple(p) for p in quad])
    assert np.allclose(cal.to_px([[0, 0]]), [[1280, 0]])
    assert np.all(cal.w_at(glass_corners_mm()) > 0)


def test_operator_moves_a_corner_and_it_round_trips_through_json(tmp_path):
    cal = default_calibration((1280, 800)).with_point((GLASS_MM[0], 0.0), (1250.0, 30.0))
    assert np.allclose(cal.to_px([[GLASS_MM[0], 0.0]]), [[1250, 30]], atol=1e-6)
    assert np.allclose(cal.to_px([[0.0, 0.0]]), [[0, 0]], atol=1e-6)
    path = tmp_path / "sim.projector.json"
    save_calibration(cal, path)
    back = load_calibration(path, (999, 999))
    assert back.frame_px == (1280, 800)
    assert np.allclose(back.h, cal.h)
    assert back.residuals_px().max() < 1e-6


def test_missing_file_gives_default_and_broken_file_is_a_user_error(tmp_path):
    cal = load_calibration(tmp_path / "none.json", (800, 600))
    assert np.allclose(cal.to_px([[GLASS_MM[0], GLASS_MM[1]]]), [[800, 600]])
    bad = tmp_path / "bad.json"
    bad.write_text('{"points": 3}')
    with pytest.raises(UserError, match="bad.json"):
        load_calibration(bad, (800, 600))


def test_render_size_scales_the_calibration():
    cal = default_calibration((1280, 800))
    assert np.allclose(
        cal.to_px([[GLASS_MM[0], GLASS_MM[1]]], size_px=(1920, 1080)), [[1920, 1080]]
    )


def test_running_projector_picks_up_the_operators_new_calibration(tmp_path):
    import os

    from plugins.projector.app import CalibrationWatcher

    path = tmp_path / "cal.json"
    w = CalibrationWatcher(path, (1280, 800), GLASS_MM)
    assert np.allclose(w.cal.to_px([[GLASS_MM[0], 0]]), [[1280, 0]])
    assert w.poll(10.0) is None  # nothing changed
    save_calibration(w.cal.with_point((GLASS_MM[0], 0.0), (1200.0, 30.0)), path)
    new = w.poll(20.0)
    assert new is not None and np.allclose(new.to_px([[GLASS_MM[0], 0]]), [[1200, 30]])
    path.write_text("{broken")  # a half-edited file keeps the last good calibration
    os.utime(path, (1, 1))
    assert w.poll(30.0) is None and np.allclose(w.cal.to_px([[GLASS_MM[0], 0]]), [[1200, 30]])


def test_operator_nudges_a_corner_from_the_keyboard_and_saves(tmp_path):
    from plugins.projector.app import CornerAdjust

    path = tmp_path / "cal.json"
    adj = CornerAdjust(default_calibration((1280, 800)), path)
    assert not adj.key("LEFT")  # keys do nothing until C starts the adjustment
    assert adj.key("C") and adj.overlay()["kind"] == "alignment"
    adj.key("_2")
    adj.key("LEFT", shift=True)
    adj.key("DOWN")
    assert adj.corner_px() == pytest.approx((1270.0, 1.0))
    assert "corner 2 at (1270, 1)" in adj.overlay()["message"]
    adj.key("ESCAPE")  # cancel: back to the saved calibration, nothing written
    assert not adj.active and not path.exists()
    adj.key("C")
    adj.key("3")
    for _ in range(5):
        adj.key("UP", shift=True)
    adj.key("RETURN")
    assert not adj.active
    back = load_calibration(path, (1, 1))
    assert np.allclose(back.to_px([[GLASS_MM[0], GLASS_MM[1]]]), [[1280, 750]])
    # a nudge that would fold the glass is refused with a note
    adj.key("C")
    adj.key("3")
    for _ in range(200):
        adj.key("LEFT", shift=True)
    assert "fold" in adj.overlay()["message"]
    assert adj.corner_px()[0] > 0
