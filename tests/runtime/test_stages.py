"""Shared stages: camera -> table mapping, vision on the twin, the classifier's own
classify stage (its gesture rules: tests/gestures/test_rules.py)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from console.runtime.stages import (
    SMALL_BATCH,
    VisionStage,
    base_stages,
    corners_homography,
    fallback_to_mm,
    learn_background,
    open_camera,
    open_classifier,
)


def test_corners_homography_maps_the_corners_exactly():
    corners = [600.0, 20.0, 40.0, 30.0, 50.0, 450.0, 590.0, 440.0]
    to_mm = corners_homography(corners, (700.0, 400.0))
    px = np.array(corners).reshape(4, 2)
    mm = to_mm(px)
    assert mm == pytest.approx(np.array([[0, 0], [700, 0], [700, 400], [0, 400]]), abs=1e-6)


def test_corners_homography_gives_the_stacked_product_bit_for_bit():
    # the points made homogeneous in place: the same product as column_stack's, every bit
    corners = [12.5, 20.1, 630.2, 15.3, 625.0, 470.9, 8.1, 466.0]
    to_mm = corners_homography(corners, (800.0, 600.0))
    src = np.array(corners, np.float32).reshape(4, 2)
    dst = np.array([(0, 0), (800, 0), (800, 600), (0, 600)], np.float32)
    hm = cv2.getPerspectiveTransform(src, dst).astype(np.float64)
    rng = np.random.default_rng(0)
    for n in (0, 1, 2, 3, 7, 8, 9, 400):
        p = rng.uniform(-10.0, 650.0, (n, 2))
        q = np.column_stack([p, np.ones(n)]) @ hm.T
        if n > SMALL_BATCH:
            np.testing.assert_array_equal(to_mm(p), q[:, :2] / q[:, 2:3])
        else:  # a frame's few points in Python floats: the last places may differ
            assert to_mm(p).shape == (n, 2)
            np.testing.assert_allclose(to_mm(p), q[:, :2] / q[:, 2:3], rtol=1e-14, atol=1e-12)
    assert to_mm((320.5, 240.25)).shape == (1, 2)


@pytest.fixture
def twin(profile, plugins):
    cam = open_camera(profile, plugins)
    cam.realtime = False
    yield cam
    cam.close()


def test_twin_contacts_land_where_the_ground_truth_says(profile, plugins, twin):
    from plugins.twin.camera.camera import SequenceScript

    twin.set_script(
        SequenceScript(
            [("two_finger", "s1", None, 40)],
            table_mm=(743.46, 447.29),
            gap_frames=0,
            loop=True,
            seed=3,
        )
    )
    clf = open_classifier(profile, plugins)
    learn_background(twin, clf)
    stage = VisionStage(clf)
    errs = []
    for _ in range(6):
        f = twin.read()
        work: dict = {}
        stage(f, work)
        truth = np.array(twin.truth["contacts_mm"])
        for c in work["contacts"]:
            assert c.pos_mm is not None
            errs.append(np.hypot(*(truth - c.pos_mm).T).min())
        assert work["hand"] is not None and work["hand"].center_mm is not None
    assert len(errs) >= 6
    assert np.median(errs) < 6.0  # mm: a fingertip is ~15 mm wide


def test_no_fallback_mapping_off_the_twin(profile, plugins):
    class P:
        def get(self, key, default=None):
            return {"camera.driver": "opencv"}.get(key, profile.get(key, default))

    assert fallback_to_mm(P(), plugins) is None
    assert fallback_to_mm(profile, plugins) is not None


def test_the_classify_stage_is_the_classifier_s():
    """The gesture rules are the classifier's (``Classifier.gesture_stage``): the shared
    stages hold none."""

    class Clf:
        to_mm = None

        def gesture_stage(self):
            return stage

    def stage(frame, work):
        work["gesture"] = None

    assert [(n, fn) for n, fn in base_stages(Clf())][1] == ("classify", stage)


def test_console_names_no_gesture():
    """console/ builds no ``Gesture``: naming one (a resting hand, a grip, the model's
    decision) is the classifier plugin's (plugins/gestures/rules.py)."""
    import ast
    from pathlib import Path

    import console

    root = Path(console.__file__).parent
    found = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call):
                f = node.func
                name = f.id if isinstance(f, ast.Name) else getattr(f, "attr", "")
                if name == "Gesture":
                    found.append(f"{path.relative_to(root.parent)}:{node.lineno}")
    assert found == []
