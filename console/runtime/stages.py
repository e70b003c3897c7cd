"""Stages every loop shares: vision (through the registered classifier) and gesture
recognition, the camera -> table mapping the twin uses without a touch calibration, and
``vision_loop`` (camera + vision + gestures + sinks: what TUIO alone needs).

Stage functions take ``(frame, work)`` (see ``console.runtime.loop``); they put their
results in ``work``: ``result`` (the vision result: ``hands``, ``contacts``), ``hand``
(the largest hand or ``None``), ``contacts`` (contacts with ``pos_mm``), ``gesture``.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from console.contracts import Classifier, RendersBackground
from console.errors import UserError
from console.types import Frame, Gesture, Hand


def corners_homography(
    corners_px: list[float], table_mm: tuple[float, float], scale: tuple[float, float] = (1, 1)
):
    """px -> mm from the four glass corners' pixels (order (0,0) (W,0) (W,H) (0,H))."""
    import cv2

    w, h = table_mm
    src = np.array(
        [(corners_px[2 * i] * scale[0], corners_px[2 * i + 1] * scale[1]) for i in range(4)],
        np.float64,
    )
    dst = np.array([(0, 0), (w, 0), (w, h), (0, h)], np.float64)
    hm = cv2.getPerspectiveTransform(src.astype(np.float32), dst.astype(np.float32))
    hm = hm.astype(np.float64)

    def to_mm(pts_px: np.ndarray) -> np.ndarray:
        p = np.asarray(pts_px, dtype=np.float64).reshape(-1, 2)
        q = np.column_stack([p, np.ones(len(p))]) @ hm.T
        return q[:, :2] / q[:, 2:3]

    return to_mm


def fallback_to_mm(profile: Any, plugins: Any = None):
    """Without a touch calibration: a simulated camera's glass corners from the profile
    (``[twin_camera] corners_px``), else ``None`` (positions stay in pixels). Whether the
    camera is simulated is its registration's to say (``plugins.simulated``)."""
    corners = profile.get("twin_camera.corners_px")
    if plugins is None:
        from console.plugins import load_plugins

        plugins = load_plugins()
    if not corners or not plugins.simulated("camera", profile):
        return None
    w, h = float(profile.get("table.width_mm")), float(profile.get("table.height_mm"))
    sx = float(profile.get("camera.width_px", 640)) / 640.0
    sy = float(profile.get("camera.height_px", 480)) / 480.0
    return corners_homography(list(corners), (w, h), (sx, sy))


def open_classifier(profile: Any, plugins: Any) -> Classifier:
    """The profile's classifier, checked against ``console.contracts.Classifier`` (its
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
        work["hands"] = hands
        work["hand"] = hands[0] if hands else None
        work["contacts"] = tracks.contacts


@dataclass
class StillHand:
    """A hand resting on the table: present and within ``still_mm`` for ``still_s``.

    ``update(t_s, pos_mm)`` returns the resting position once per placement; it re-arms
    when the hand lifts for ``lift_s`` or moves more than ``moved_mm`` away.
    """

    still_mm: float = 12.0
    still_s: float = 0.3
    lift_s: float = 0.2
    moved_mm: float = 40.0
    _hist: deque = field(default_factory=deque, repr=False)
    _absent_since: float | None = None
    _fired_at: tuple[float, float] | None = None

    def reset(self) -> None:
        self._hist.clear()
        self._fired_at = None

    def update(self, t_s: float, pos_mm: tuple[float, float] | None) -> tuple[float, float] | None:
        if pos_mm is None:
            if self._absent_since is None:
                self._absent_since = t_s
            if t_s - self._absent_since >= self.lift_s:
                self.reset()
            return None
        self._absent_since = None
        p = np.asarray(pos_mm, dtype=float)
        if self._fired_at is not None:
            if np.hypot(*(p - self._fired_at)) <= self.moved_mm:
                return None
            self.reset()
        if self._hist and np.hypot(*(p - self._hist[0][1])) > self.still_mm:
            self._hist.clear()  # moving: start over from here
        self._hist.append((t_s, p))
        if t_s - self._hist[0][0] < self.still_s:
            return None
        pts = np.array([q for _, q in self._hist])
        c = pts.mean(0)
        self._fired_at = (float(c[0]), float(c[1]))
        return self._fired_at


class GestureStage:
    """Stage ``classify``: a gesture for the frame, or ``None``.

    Rules on the vision result name what the demos act on: ``static_hand`` (a hand
    resting still, once per placement), ``two_finger`` (two contacts on one hand:
    the knob's grip). When the classifier has a trained model it names the gesture of a
    new placement from its first frames (``[gestures] frames``) once.
    """

    def __init__(self, classifier: Any, still: StillHand | None = None) -> None:
        self.clf = classifier
        self.still = still or StillHand()
        self.window: deque[Frame] = deque(maxlen=6)
        self._named = False
        self.last: Gesture | None = None
        self._palms: deque[tuple[float, np.ndarray]] = deque(maxlen=600)

    def _settle_palm(self, t_s: float, palm: Any) -> tuple[float, float] | None:
        """The mean palm position over the still window (since the tracked hand came to
        rest within ``still_mm``), or None without a hand."""
        if palm is None:
            self._palms.clear()
            return None
        hist = self.still._hist
        t0 = hist[0][0] if hist else t_s
        self._palms.append((t_s, np.asarray(palm, float)))
        while self._palms and self._palms[0][0] < t0:
            self._palms.popleft()
        c = np.mean([q for _, q in self._palms], axis=0)
        return (float(c[0]), float(c[1]))

    def __call__(self, frame: Frame, work: dict) -> None:
        hand: Hand | None = work.get("hand")
        t = frame.t_capture_s
        pos = hand.center_mm if hand is not None else None
        if hand is not None and pos is None:
            pos = hand.center_px
        palm = pos
        tracks = work.get("tracks")  # stillness of the tracked centre: the palm's can jump
        if hand is not None and tracks is not None and tracks.in_mm and tracks.hand_tracks:
            pos = tuple(tracks.hand_tracks[0].pos)
        rest = self.still.update(t, pos)
        settle = self._settle_palm(t, palm)
        if settle is not None:
            work["settle_mm"] = settle  # where the palm rests so far (the warm-up's place)
        g = None
        if rest is not None and hand is not None:
            g = Gesture("static_hand", "static", 1.0, t, hand)
            # where the palm rests: over the still window, as the warm-up saw it (one
            # frame's palm can jump by centimetres between two views of a resting hand)
            work["rest_mm"] = rest if pos is palm else (settle or palm)
        elif hand is not None and len(hand.contacts) == 2:
            g = Gesture("two_finger", "static", 1.0, t, hand)
        if hand is None:
            self.window.clear()
            self._named = False
        else:
            self.window.append(frame)
            n = self.clf.n_frames  # 0: no trained model
            if n > 0 and not self._named and len(self.window) >= n:
                self._named = True
                named = self.clf.classify(list(self.window))
                if named is not None:
                    g = named
        work["gesture"] = g
        if g is not None:
            self.last = g


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


def base_stages(classifier: Any, gestures: GestureStage | None = None) -> list:
    """``vision`` then ``classify``."""
    return [("vision", VisionStage(classifier)), ("classify", gestures or GestureStage(classifier))]


def vision_loop(profile: Any, plugins: Any, camera: Any, *, sinks=(), extra_stages=()):
    """A ``FrameLoop``: camera -> vision -> classify (+ extra stages) -> sinks."""
    from console.runtime.latency import LatencyMonitor
    from console.runtime.loop import FrameLoop

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
