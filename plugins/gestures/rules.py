"""The live gesture rules: what the frame loop's ``classify`` stage names on each frame.

``GestureRules`` is the stage the classifier hands the loop (``SvmClassifier.gesture_stage``,
``console.core.contracts.Classifier``). It reads what the ``vision`` stage put in ``work``
(``result``: the frame's vision result; ``hand``, ``tracks``) and names:

- ``static_hand``: a hand resting still (``StillHand``), once per placement; ``rest_mm``
  is where its palm rests, ``settle_mm`` where it rests so far (every frame with a hand);
- ``two_finger``: two contacts on one hand (the knob's grip);
- once per placement, the gesture the classifier's model names from the vision results of
  the placement's first ``n_frames`` frames (``named``: on that frame, the gesture or
  ``None``). The results are the loop's own: no frame goes through the vision twice.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from console.plugin_api import Classifier, Frame, Gesture, Hand, VisionResult

#: vision results kept for the model's decision (``[gestures] frames`` is at most 6)
WINDOW_FRAMES = 6


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

    def since_s(self) -> float | None:
        """When the hand came to rest within ``still_mm`` (``None``: not resting)."""
        return self._hist[0][0] if self._hist else None

    def update(self, t_s: float, pos_mm: tuple[float, float] | None) -> tuple[float, float] | None:
        if pos_mm is None:
            if self._absent_since is None:
                self._absent_since = t_s
            if t_s - self._absent_since >= self.lift_s:
                self.reset()
            return None
        self._absent_since = None
        x, y = float(pos_mm[0]), float(pos_mm[1])  # plain floats: a few per frame
        if self._fired_at is not None:
            if math.hypot(x - self._fired_at[0], y - self._fired_at[1]) <= self.moved_mm:
                return None
            self.reset()
        if self._hist:
            x0, y0 = self._hist[0][1]
            if math.hypot(x - x0, y - y0) > self.still_mm:
                self._hist.clear()  # moving: start over from here
        self._hist.append((t_s, (x, y)))
        if t_s - self._hist[0][0] < self.still_s:
            return None
        pts = np.array([q for _, q in self._hist])
        c = pts.mean(0)
        self._fired_at = (float(c[0]), float(c[1]))
        return self._fired_at


class PalmWindow:
    """The last ``size`` palm positions (x, y) with their times, oldest first, kept in one
    array: ``mean_since(t0)`` drops those older than ``t0`` and averages the rest, the
    value ``np.mean`` of the positions' list gives (the same rows in the same order),
    without stacking up to ``size`` positions again on every frame."""

    def __init__(self, size: int) -> None:
        self.size = int(size)
        self._t = np.empty(2 * self.size)
        self._xy = np.empty((2 * self.size, 2))
        self._a = self._b = 0  # the kept rows: [a, b)

    def __len__(self) -> int:
        return self._b - self._a

    def clear(self) -> None:
        self._a = self._b = 0

    def append(self, t_s: float, xy: Any) -> None:
        if self._b == len(self._t):  # the end reached: the kept rows move to the front
            n = self._b - self._a
            self._t[:n] = self._t[self._a : self._b]
            self._xy[:n] = self._xy[self._a : self._b]
            self._a, self._b = 0, n
        self._t[self._b] = t_s
        self._xy[self._b] = xy
        self._b += 1
        if self._b - self._a > self.size:
            self._a += 1

    def mean_since(self, t0_s: float) -> np.ndarray:
        """The mean position of those kept from ``t0_s`` on (NaN when none is)."""
        while self._a < self._b and self._t[self._a] < t0_s:
            self._a += 1
        n = self._b - self._a
        if n == 0:
            return np.full(2, np.nan)
        # np.mean's sum and division by the count, without its wrapper's cost
        return np.add.reduce(self._xy[self._a : self._b], axis=0) / n


class GestureRules:
    """Stage ``classify``: ``work["gesture"]`` for the frame, or ``None`` (see the module).

    ``classifier`` decides a placement's gesture (``n_frames``, ``classify(window, t_s)``)
    from the vision results this stage keeps (``window``, cleared when the hand lifts).
    """

    def __init__(self, classifier: Classifier, still: StillHand | None = None) -> None:
        self.clf = classifier
        self.still = still or StillHand()
        self.window: deque[VisionResult] = deque(maxlen=WINDOW_FRAMES)
        self._named = False
        self.last: Gesture | None = None
        self._palms = PalmWindow(600)

    def _settle_palm(self, t_s: float, palm: Any) -> tuple[float, float] | None:
        """The mean palm position over the still window (since the tracked hand came to
        rest within ``still_mm``), or None without a hand."""
        if palm is None:
            self._palms.clear()
            return None
        t0 = self.still.since_s()
        t0 = t_s if t0 is None else t0
        self._palms.append(t_s, palm)
        c = self._palms.mean_since(t0)
        return (float(c[0]), float(c[1]))

    def _decide(self, result: VisionResult, t_s: float, work: dict) -> Gesture | None:
        """Once per placement, the model's gesture from its first ``n_frames`` vision
        results (``work["named"]`` on that frame); a result is kept only until then (none
        without a model): each holds its frame's images."""
        n = self.clf.n_frames  # 0: no trained model
        if n <= 0 or self._named:  # nothing to decide: no result kept (nor its images)
            return None
        self.window.append(result)
        if len(self.window) < n:
            return None
        self._named = True
        named = self.clf.classify(list(self.window), t_s)
        work["named"] = named
        return named

    def __call__(self, frame: Frame, work: dict) -> None:
        hand: Hand | None = work.get("hand")
        t = frame.t_capture_s
        pos = hand.center_mm if hand is not None else None
        if hand is not None and pos is None:
            pos = hand.center_px
        palm = pos
        tracks = work.get("tracks")  # stillness of the tracked centre: the palm's can jump
        if hand is not None and tracks is not None and tracks.in_mm and tracks.hand_tracks:
            tr = tracks.hand_tracks[0]
            pos = (tr.x, tr.y)
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
            named = self._decide(work["result"], t, work)
            if named is not None:
                g = named
        work["gesture"] = g
        if g is not None:
            self.last = g
