"""A demo's twin camera rendering in its own process (``[runtime] twin_camera_process``:
the twin's ``apart()``) delivers the scripted demo's frames."""

from __future__ import annotations

import numpy as np


def _open(profile, plugins, demo):
    from plugins.demos.run import _open_camera

    cam = _open_camera(profile, plugins, demo)
    assert cam.status().get("process"), "the twin renders in its own process"
    return cam


def test_process_camera_delivers_the_scripted_hand_and_cleans_up(profile, plugins):
    cam = _open(profile, plugins, "knob")
    try:
        bg = cam.background()
        assert bg.shape == (
            int(profile.get("camera.height_px")),
            int(profile.get("camera.width_px")),
        )
        frames = [f for f in (cam.read(2.0) for _ in range(40)) if f is not None]
        assert len(frames) >= 30
        seqs = [f.seq for f in frames]
        assert seqs == sorted(set(seqs)), "frames in camera order, none twice"
        assert all(
            b.t_capture_s > a.t_capture_s for a, b in zip(frames[:-1], frames[1:], strict=True)
        )
        # the scripted hand rotates on the table: the frames differ from the empty table
        diff = [np.abs(f.image.astype(int) - bg).mean() for f in frames]
        assert max(diff) > 1.0
        assert cam.status()["alive"]
    finally:
        cam.close()
    assert not cam.status()["alive"], "the camera process ended"
    assert cam.read(0.1) is None


def _hand_centroid_px(cam, bg) -> np.ndarray:
    """Where the newest frames differ from the empty table (pixels)."""
    import time

    time.sleep(0.4)  # the command reaches the child, its next frames show it
    frames = [f for f in (cam.read(2.0) for _ in range(12)) if f is not None]
    moved = np.abs(frames[-1].image.astype(int) - bg) > 30
    ys, xs = np.nonzero(moved)
    assert xs.size > 200, "a hand is on the table"
    return np.array([xs.mean(), ys.mean()])


def test_the_operators_hand_reaches_the_twin_in_its_own_process(profile, plugins):
    """``set_target`` crosses to the child: the hand shows where the operator put it."""
    cam = _open(profile, plugins, "flow")
    try:
        bg = cam.background().astype(int)
        cam.set_target((200.0, 150.0))
        a = _hand_centroid_px(cam, bg)
        cam.set_target((600.0, 300.0))
        b = _hand_centroid_px(cam, bg)
        # 400 mm along the table is over 250 px in the 640 px image
        assert np.hypot(*(b - a)) > 250
        # the mapping stays with the parent: targets are drawn on the demo's view
        assert cam.mm_to_px((200.0, 150.0)) is not None
        assert cam.status()["alive"]
    finally:
        cam.close()
    cam.set_target(None)  # closed: nothing to tell, no error
