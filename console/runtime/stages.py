"""Stages every loop shares: vision (through the registered classifier) and the
classifier's own ``classify`` stage (its gesture rules: ``Classifier.gesture_stage``), the
camera -> table mapping the twin uses without a touch calibration, and ``vision_loop``
(camera + vision + gestures + sinks: what TUIO alone needs).

Stage functions take ``(frame, work)`` (see ``console.runtime.loop``); they put their
results in ``work``: ``result`` (the vision result: ``hands``, ``contacts``), ``tracks``,
``hands``, ``hand`` (the largest hand or ``None``), ``contacts`` (contacts with
``pos_mm``); the gesture stage ``gesture`` (or ``None``), ``rest_mm`` and ``settle_mm``
(where a resting palm rests), ``named`` (on the frame the model decided on). Each frame
goes through the vision once: the gesture stage decides from the ``result``s in ``work``.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from console.core.contracts import Classifier, RendersBackground
from console.core.errors import UserError
from console.core.types import Frame, Hand
from console.runtime.latency import LatencyMonitor
from console.runtime.loop import FrameLoop

#: up to this many points, ``corners_homography``'s mapping is worked in Python floats: a
#: third of the matrix product's cost (its arrays and BLAS call) for the few points a frame
#: maps; the product's rounding differs from it by a few units in the last place (and the
#: product's own bits change with the number of points it is given)
SMALL_BATCH = 8


def corners_homography(
    corners_px: list[float], table_mm: tuple[float, float], scale: tuple[float, float] = (1, 1)
):
    """px -> mm from the four glass corners' pixels (order (0,0) (W,0) (W,H) (0,H)): an
    (n, 2) array of the points' mm."""
    import cv2

    w, h = table_mm
    src = np.array(
        [(corners_px[2 * i] * scale[0], corners_px[2 * i + 1] * scale[1]) for i in range(4)],
        np.float64,
    )
    dst = np.array([(0, 0), (w, 0), (w, h), (0, h)], np.float64)
    hm = cv2.getPerspectiveTransform(src.astype(np.float32), dst.astype(np.float32))
    hmt = hm.astype(np.float64).T
    (ax, ay, a1), (bx, by, b1), (wx, wy, w1) = hm.astype(np.float64).tolist()

    def to_mm(pts_px: np.ndarray) -> np.ndarray:
        p = np.asarray(pts_px, dtype=np.float64).reshape(-1, 2)
        if len(p) <= SMALL_BATCH:  # a frame's hands and fingertips: plain floats
            return np.array(
                [
                    ((x * ax + y * ay + a1) / w, (x * bx + y * by + b1) / w)
                    for x, y in p.tolist()
                    for w in (x * wx + y * wy + w1,)
                ]
            ).reshape(-1, 2)
        q = np.ones((len(p), 3))  # homogeneous points (x, y, 1), filled in place
        q[:, :2] = p
        q = q @ hmt
        return q[:, :2] / q[:, 2:3]

    return to_mm


def fallback_to_mm(profile: Any, plugins: Any):
    """Without a touch calibration: a simulated camera's glass corners from the profile
    (``[twin_camera] corners_px``), else ``None`` (positions stay in pixels). Whether the
    camera is simulated is its registration's to say (``plugins.simulated``)."""
    corners = profile.get("twin_camera.corners_px")
    if not corners or not plugins.simulated("camera", profile):
        return None
    w, h = float(profile.get("table.width_mm")), float(profile.get("table.height_mm"))
    sx = float(profile.get("camera.width_px", 640)) / 640.0
    sy = float(profile.get("camera.height_px", 480)) / 480.0
    return corners_homography(list(corners), (w, h), (sx, sy))


def open_classifier(profile: Any, plugins: Any) -> Classifier:
    """The profile's classifier, checked against ``console.core.contracts.Classifier`` (its
    per-frame vision included); positions in mm through ``fallback_to_mm`` when it has
    no calibration of its own."""
    clf = plugins.build("classifier", profile.get("gestures.classifier") or "svm", profile)
    if clf.to_mm is None:
        clf.to_mm = fallback_to_mm(profile, plugins)
    return clf


class VisionStage:
    """Stage ``vision``: the classifier's pipeline on one frame, then the hands and
    contacts followed with ids (``console.runtime.tracking``): ``work["tracks"]`` is the
    frame's ``TrackFrame``; ``contacts`` (and each hand's) carry their track ids."""

    def __init__(self, classifier: Any) -> None:
        # lazy: SciPy loads only when tracking runs
        from console.runtime.tracking import Tracking

        self.clf = classifier
        self.tracking = Tracking(classifier.to_mm)

    def __call__(self, frame: Frame, work: dict) -> None:
        res = self.clf.process(frame)
        work["result"] = res
        self.tracking.to_mm = self.clf.to_mm  # a touch calibration may replace it
        tracks = self.tracking.update(frame.t_capture_s, tuple(res.hands), tuple(res.contacts))
        hands: tuple[Hand, ...] = tracks.hands
        work["tracks"] = tracks
        work["to_mm"] = self.clf.to_mm  # camera px -> table mm (or None): TUIO 2.0 outlines
        work["hands"] = hands
        work["hand"] = hands[0] if hands else None
        work["contacts"] = tracks.contacts


def open_camera(profile: Any, plugins: Any) -> Any:
    """The profile's camera (``[camera] driver``), opened through its registration."""
    reg = plugins.get("camera", profile.get("camera.driver"))
    try:
        return plugins.build("camera", reg.name, profile)
    except UserError:
        raise
    except Exception as exc:
        raise UserError(
            f"camera {reg.name!r} failed to open: {exc}; run `haptable doctor` for the fix"
        ) from None


def learn_background(camera: Any, classifier: Any) -> None:
    """Give the classifier the empty table (the twin can render it with hands on it)."""
    if isinstance(camera, RendersBackground):
        classifier.set_background(camera.background())


def base_stages(classifier: Any, gestures: Callable[[Frame, dict], Any] | None = None) -> list:
    """``vision`` then ``classify`` (``gestures``, else the classifier's gesture stage)."""
    return [
        ("vision", VisionStage(classifier)),
        ("classify", gestures or classifier.gesture_stage()),
    ]


def vision_loop(profile: Any, plugins: Any, camera: Any, *, sinks=(), extra_stages=()):
    """A ``FrameLoop``: camera -> vision -> classify (+ extra stages) -> sinks."""
    clf = open_classifier(profile, plugins)
    learn_background(camera, clf)
    stages = [*base_stages(clf), *extra_stages]
    rt = profile.section("runtime")
    mon = LatencyMonitor([n for n, _ in stages], size=int(rt.get("latency_window_frames", 1200)))
    return FrameLoop(
        camera,
        stages,
        monitor=mon,
        queue_size=int(rt.get("queue_frames", 2)),
        sinks=[s for s in sinks if s is not None],
    )
