"""A frame is seen once (issue 26): through a real frame loop on the camera twin, the
classifier's background model learns from every frame exactly once and in frame order,
and the model's decision takes the ``vision`` stage's results: each frame keeps the
``vision`` stamp the loop gave it, the gesture the time of the frame it was decided on."""

from __future__ import annotations

import numpy as np

from console.core.types import GestureScript, GestureStep
from console.runtime.loop import FrameLoop
from console.runtime.stages import base_stages, learn_background, open_camera, open_classifier


class NamingModel:
    """A trained model's surface (``decide``): names every placement ``l_shape`` from
    its first 3 frames, whatever the features (the rules never name ``l_shape``)."""

    n_frames = 3
    n_harmonics = 4
    motion_threshold = 0.1

    def predict(self, xs, xd, xk) -> np.ndarray:
        return np.array(["l_shape"])

    def confidence(self, xs, xd, xk) -> np.ndarray:
        return np.array([0.9])


def test_the_background_sees_each_frame_once_in_order_and_the_vision_stamp_is_the_loops(
    profile, plugins
):
    cam = open_camera(profile, plugins)
    cam.realtime = False
    # two placements of an open hand, an empty table before each
    steps = (GestureStep("open_hand", "s1", None, 14),)
    cam.set_script(GestureScript(steps, gap_frames=8, loop=True, seed=2))
    try:
        clf = open_classifier(profile, plugins)
        learn_background(cam, clf)
        clf.model = NamingModel()
        fed: list[np.ndarray] = []  # the images the background model learnt from
        learn = clf.background.update

        def update(image, *args, **kw):
            fed.append(image)
            return learn(image, *args, **kw)

        clf.background.update = update
        vision_stamps: dict[int, list[float]] = {}  # per frame, as each process left it
        run = clf.process

        def process(frame):
            res = run(frame)
            vision_stamps.setdefault(frame.seq, []).append(frame.stamps_s["vision"])
            return res

        clf.process = process
        loop = FrameLoop(cam, base_stages(clf))
        frames, decided = [], []
        for _ in range(44):
            f = cam.read()
            frames.append(f)
            g = loop.process(f).get("gesture")
            if g is not None and g.name == "l_shape":
                decided.append((f, g))
    finally:
        cam.close()
    assert loop.monitor.snapshot()["errors"] == 0
    # once and in order: the frames' own images, one update each
    assert len(fed) == len(frames)
    assert all(a is f.image for a, f in zip(fed, frames, strict=True))
    # each frame through the vision once; its stamp is the one the vision stage gave it
    assert sorted(vision_stamps) == [f.seq for f in frames]
    assert all(len(v) == 1 for v in vision_stamps.values())
    for f in frames:
        assert f.stamps_s["vision"] == vision_stamps[f.seq][0] <= f.stamps_s["classify"]
    # the model decided each placement once, at the time of the frame it decided on
    assert len(decided) == 2
    for f, g in decided:
        assert g.t_s == f.t_capture_s and g.hand is not None
