"""The twin camera rendering in its own process delivers the scripted demo's frames."""

from __future__ import annotations

import numpy as np


def test_process_camera_delivers_the_scripted_hand_and_cleans_up(profile):
    from plugins.demos.camproc import ProcessCamera

    cam = ProcessCamera(profile, "knob")
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
