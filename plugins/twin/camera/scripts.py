"""What the twin camera's hands do, frame by frame: ``Script.hands(k, t_s, rng)``.

- ``IdleScript``: the empty table.
- ``SequenceScript``: gestures one after another with idle gaps (loops).
- ``TouchScript``: a finger touches given table points in turn (touch calibration).
- ``HoldScript``: static gestures held in place, with tremor; ``Together``: several
  scripts at once; ``demo_script``: every gesture once, the console's default view.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from .gestures import DYNAMIC, GESTURES, SIDES, plan_take, take_pose
from .hand import FingerPose, HandPose, Subject, hand_pieces, make_subject

Hands = list[tuple[Subject, HandPose]]


class Script(Protocol):
    """What the camera shows at frame ``k`` (time ``t_s``): hands, label, extra truth."""

    def hands(self, k: int, t_s: float, rng: np.random.Generator) -> tuple[Hands, str, dict]: ...


class IdleScript:
    """The empty table."""

    name = "idle"

    def hands(self, k, t_s, rng):
        return [], "idle", {}


@dataclass
class _Item:
    gesture: str
    subject: Subject
    side: str | None
    n_frames: int
    start: int = 0
    take: Any = None


class SequenceScript:
    """Gestures in turn, ``gap_frames`` of empty table before each; loops if asked.

    ``items``: (gesture, subject name, hand side or None, frames or None) tuples."""

    name = "sequence"

    def __init__(
        self,
        items: list[tuple[str, str, str | None, int | None]],
        *,
        table_mm: tuple[float, float],
        fps: float = 60.0,
        gap_frames: int = 30,
        loop: bool = True,
        subject_seed: int = 0,
        seed: int = 0,
    ) -> None:
        self.items: list[_Item] = []
        self.table_mm, self.fps, self.gap, self.loop = table_mm, fps, gap_frames, loop
        self._rng = np.random.default_rng(seed)
        self._subject_seed = subject_seed
        self._end = 0
        for it in items:
            self.add(*it)

    def add(
        self,
        gesture: str,
        subject: str = "s1",
        side: str | None = None,
        n_frames: int | None = None,
        *,
        at: int | None = None,
    ) -> None:
        """Append a gesture (starting after a gap, no earlier than frame ``at``)."""
        if gesture not in GESTURES:
            raise ValueError(f"unknown gesture {gesture!r}; use one of {', '.join(GESTURES)}")
        n = n_frames or (30 if gesture in DYNAMIC else 45)  # half a second, 0.75 s
        start = max(self._end, at or 0) + self.gap
        subj = make_subject(subject, self._subject_seed)
        item = _Item(gesture, subj, side, n, start)
        item.take = plan_take(
            gesture, subj, self._rng, self.table_mm, side=side, duration_s=n / self.fps
        )
        self.items.append(item)
        self._end = start + n

    def hands(self, k, t_s, rng):
        if not self.items:
            return [], "idle", {}
        if self.loop and self._end > 0:
            k = k % self._end
        for it in self.items:
            if it.start <= k < it.start + it.n_frames:
                t = (k - it.start) / self.fps
                return (
                    [(it.subject, take_pose(it.take, t, rng))],
                    it.gesture,
                    {"gesture_frame": k - it.start},
                )
        return [], "idle", {}


def _touch_pose(
    subject: Subject,
    target_mm: np.ndarray,
    heading_deg: float,
    side: str,
    touching: bool,
    hover_mm: float,
) -> HandPose:
    """A pointing hand whose index contact (or hovering tip) is at ``target_mm``."""
    curl = FingerPose((70, 95, 45), 0.0, False, subject.lift_mm)
    thumb = FingerPose((25, 35, 25), -5, False, subject.lift_mm + 6)
    index = (
        FingerPose((0, 15, 10), 0.0, True)
        if touching
        else FingerPose((0, 15, 10), 0.0, False, hover_mm)
    )
    hp = subject.palm_lift_mm
    pose = HandPose((0.0, 0.0), heading_deg, side, (hp + 5, hp), (thumb, index, curl, curl, curl))
    geo = hand_pieces(subject, pose)
    if touching and geo.contacts:
        at = np.array(geo.contacts[0]["pos_mm"])
    else:
        at = np.array(geo.tips_mm["index"][:2])
    d = np.asarray(target_mm, dtype=float) - at
    return pose.moved((float(d[0]), float(d[1])))


def _heading_towards(p_mm: np.ndarray, table_mm: tuple[float, float]) -> float:
    """The operator reaches from the nearest table edge."""
    w, h = table_mm
    dist = {"bottom": p_mm[1], "top": h - p_mm[1], "left": p_mm[0], "right": w - p_mm[0]}
    edge = min(dist, key=dist.get)
    return dict(SIDES)[edge]


class TouchScript:
    """A finger touches each point in turn: hover ``approach_frames``, touch
    ``dwell_frames``, then ``gap_frames`` of empty table. Loops over the points."""

    name = "touch"

    def __init__(
        self,
        points_mm,
        *,
        table_mm: tuple[float, float],
        subject: str = "s1",
        side: str = "right",
        dwell_frames: int = 20,
        approach_frames: int = 6,
        gap_frames: int = 12,
        error_mm: float = 1.5,
        bias_mm: float = 2.0,
        subject_seed: int = 0,
        seed: int = 0,
        loop: bool = True,
    ) -> None:
        self.points = np.asarray(points_mm, dtype=float).reshape(-1, 2)
        self.table_mm = table_mm
        self.subject = make_subject(subject, subject_seed)
        self.side = side
        self.dwell, self.approach, self.gap = dwell_frames, approach_frames, gap_frames
        self.loop = loop
        rng = np.random.default_rng(seed)
        self.headings = [_heading_towards(p, table_mm) + rng.normal(0, 10) for p in self.points]
        self.hits = []  # where each touch really lands (mm)
        for p, hd in zip(self.points, self.headings, strict=True):
            back = -np.array([np.cos(np.radians(hd)), np.sin(np.radians(hd))])
            self.hits.append(p + bias_mm * back + rng.normal(0, error_mm, 2))
        self.period = self.approach + self.dwell + self.gap

    def hands(self, k, t_s, rng):
        n = len(self.points)
        if n == 0:
            return [], "idle", {}
        i, j = divmod(k, self.period)
        if i >= n and not self.loop:
            return [], "idle", {}
        i %= n
        extra = {"target_index": int(i), "target_mm": [float(v) for v in self.points[i]]}
        if j >= self.approach + self.dwell:
            return [], "idle", extra
        touching = j >= self.approach
        hover = 3.0 + 4.0 * (self.approach - j) if not touching else 0.0
        pose = _touch_pose(self.subject, self.hits[i], self.headings[i], self.side, touching, hover)
        pose = pose.moved(tuple(rng.normal(0, 0.15, 2)))
        extra["touching"] = touching
        return [(self.subject, pose)], "touch" if touching else "hover", extra


class Together:
    """Several scripts at once (e.g. one hand per script): hands and truth merged; the
    first script's extra truth is kept, the others' are listed under ``"others"``."""

    name = "together"

    def __init__(self, scripts: list[Script]) -> None:
        self.scripts = scripts

    def hands(self, k, t_s, rng):
        hands: Hands = []
        labels, extras = [], []
        for sc in self.scripts:
            h, label, extra = sc.hands(k, t_s, rng)
            hands += h
            labels.append(label)
            extras.append(extra)
        label = next((lb for lb in labels if lb != "idle"), "idle")
        extra = dict(extras[0]) if extras else {}
        if len(extras) > 1:
            extra["others"] = extras[1:]
        return hands, label, extra


class HoldScript:
    """Hands held in place (static gestures), with tremor."""

    name = "hold"

    def __init__(self, takes: list) -> None:
        self.takes = takes

    def hands(self, k, t_s, rng):
        hands = [(tk.subject, take_pose(tk, 0.0, rng)) for tk in self.takes]
        label = self.takes[0].gesture if self.takes else "idle"
        return hands, label, {}


class _Delayed:
    """Run ``inner`` from frame ``start`` on (empty table before)."""

    def __init__(self, inner: Script, start: int) -> None:
        self.inner, self.start = inner, start
        self.name = getattr(inner, "name", "script")

    def hands(self, k, t_s, rng):
        if k < self.start:
            return [], "idle", {}
        return self.inner.hands(k - self.start, t_s, rng)


def demo_script(
    table_mm,
    fps: float,
    subject: str = "s1",
    side: str | None = None,
    gap_frames: int = 30,
    subject_seed: int = 0,
    seed: int = 0,
) -> SequenceScript:
    """Every gesture once, in the paper's order, looping (the console's default view)."""
    items = [(g, subject, side, None) for g in GESTURES]
    return SequenceScript(
        items,
        table_mm=table_mm,
        fps=fps,
        gap_frames=gap_frames,
        subject_seed=subject_seed,
        seed=seed,
    )
