"""Two-finger rotation tracking: knob angle and angular velocity from contact points.

The gesture of the paper: the thumb is a pivot, the index moves on an arc. The knob
angle follows the orientation of the line through the two fingertips (angle increases
from +x toward +y in table coordinates). Robustness:

* identity swaps: contact ids are ignored; points are matched to the two tracked fingers
  by nearest predicted position, and the line orientation is unwrapped modulo 180 deg
  by continuity (a real rotation never turns 90 deg between two frames);
* a finger lifting for a frame or two: a missing arc finger (or both) makes the filter
  predict from its velocity, for at most ``max_hold_frames`` frames; a missing pivot
  (the slower finger: the thumb) is held where it was while the arc finger still
  measures the angle, for at most ``max_pivot_hold_frames`` frames (vision often loses
  the thumb under the hand for longer). Past either limit the grip is released
  (velocity 0, angle kept);
* wrap-around: the angle is unwrapped (it runs past +/-180 deg without a jump);
* noise: an alpha-beta filter on the unwrapped angle; zero steady-state lag at constant
  velocity, lag ``a T^2 (1 - alpha) / beta`` under constant acceleration ``a`` (0.67 deg
  at 2000 deg/s^2 and 60 fps with the defaults 0.7 / 0.25). Output noise is 0.76 of the
  measurement noise; the knob's hysteresis absorbs the rest. An instant reversal of the
  hand (the twin camera's scripted rotation) overshoots by about 2 deg at ~190 deg/s.

A new grip continues from the knob angle where the last one ended (a knob does not jump
when it is re-grasped).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class RotationState:
    """Knob angle (deg, unwrapped, filtered), velocity (deg/s) and grip state at ``t_s``."""

    t_s: float
    angle_deg: float
    velocity_deg_s: float
    touching: bool
    measured: bool  # this frame carried a measurement (not a prediction)
    n_contacts: int


def wrap_deg(a: float, period: float = 360.0) -> float:
    """``a`` wrapped to (-period/2, period/2]."""
    h = period / 2
    r = math.fmod(a + h, period)
    if r <= 0:
        r += period
    return r - h


def alpha_beta_noise_ratio(alpha: float, beta: float) -> tuple[float, float]:
    """Steady-state output noise of an alpha-beta filter per unit measurement noise.

    Returns (position std ratio, velocity std ratio times T) -- Kalata's formulas.
    """
    den = alpha * (4 - 2 * alpha - beta)
    var_x = (2 * alpha**2 + 2 * beta - 3 * alpha * beta) / den
    var_v = 2 * beta**2 / den
    return math.sqrt(var_x), math.sqrt(var_v)


def _point_of(c: Any) -> tuple[float, float]:
    pos = getattr(c, "pos_mm", None)
    if pos is None:
        pos = getattr(c, "pos_px", None)
    if pos is None:
        pos = c
    return float(pos[0]), float(pos[1])


class RotationTracker:
    """Feed ``update(t_s, contacts)`` once per frame; read the returned ``RotationState``.

    ``contacts``: ``console.core.types.Contact`` objects (``pos_mm`` used when present, else
    ``pos_px``) or ``(x, y)`` pairs.
    """

    def __init__(
        self,
        alpha: float = 0.7,
        beta: float = 0.25,
        max_hold_frames: int = 3,
        start_angle_deg: float = 0.0,
        max_pivot_hold_frames: int = 30,
    ) -> None:
        if not (0 < alpha <= 1 and 0 < beta < 4 - 2 * alpha):
            raise ValueError(f"alpha-beta filter unstable for alpha={alpha}, beta={beta}")
        self.alpha, self.beta = alpha, beta
        self.max_hold_frames = int(max_hold_frames)
        self.max_pivot_hold_frames = int(max_pivot_hold_frames)
        self.angle_deg = float(start_angle_deg)
        self.velocity_deg_s = 0.0
        self.touching = False
        self._t: float | None = None
        self._fingers: np.ndarray | None = None  # (2, 2) last positions: 0 and 1
        self._speed = np.zeros(2)  # smoothed speed of each finger (mm/s): pivot = slower
        self._line_deg = 0.0  # unwrapped orientation of the finger line, mod-180 continuous
        self._offset_deg = 0.0  # knob angle minus line angle for this grip
        self._missing = [0, 0]  # consecutive frames each finger was not seen

    # ----------------------------------------------------------------- helpers
    def _release(self) -> None:
        self.touching = False
        self.velocity_deg_s = 0.0
        self._fingers = None
        self._missing = [0, 0]

    def _line_angle(self, p: np.ndarray) -> float:
        d = p[1] - p[0]
        return math.degrees(math.atan2(d[1], d[0]))

    def _measure(self, p: np.ndarray) -> float:
        """Unwrapped line orientation for finger positions ``p`` (continuous mod 180)."""
        raw = self._line_angle(p)
        self._line_deg += wrap_deg(raw - self._line_deg, 180.0)
        return self._line_deg

    def _assign(self, pts: np.ndarray, pred: np.ndarray) -> tuple[np.ndarray, list[bool]]:
        """Match points to the two fingers; return new positions and which were seen."""
        n = len(pts)
        if n >= 2:
            best, best_cost = (0, 1), math.inf
            for i in range(n):
                for j in range(n):
                    if i == j:
                        continue
                    cost = float(np.sum((pts[i] - pred[0]) ** 2) + np.sum((pts[j] - pred[1]) ** 2))
                    if cost < best_cost:
                        best, best_cost = (i, j), cost
            return np.array([pts[best[0]], pts[best[1]]]), [True, True]
        d = [float(np.sum((pts[0] - pred[k]) ** 2)) for k in (0, 1)]
        k = int(np.argmin(d))
        out = pred.copy()
        out[k] = pts[0]
        seen = [False, False]
        seen[k] = True
        return out, seen

    # ----------------------------------------------------------------- update
    def update(self, t_s: float, contacts: Sequence[Any]) -> RotationState:
        pts = np.array([_point_of(c) for c in contacts], dtype=float).reshape(-1, 2)
        pts = pts[np.all(np.isfinite(pts), axis=1)]
        dt = 0.0 if self._t is None else max(float(t_s) - self._t, 0.0)
        self._t = float(t_s)

        if not self.touching:
            if len(pts) < 2:
                return self._state(t_s, measured=False, n=len(pts))
            # new grip: the two points farthest apart (a third contact is a stray)
            if len(pts) > 2:
                dd = np.sum((pts[:, None] - pts[None]) ** 2, axis=-1)
                i, j = np.unravel_index(int(np.argmax(dd)), dd.shape)
                pts = pts[[i, j]]
            self._fingers = pts[:2].copy()
            self._speed[:] = 0.0
            self._line_deg = self._line_angle(self._fingers)
            self._offset_deg = self.angle_deg - self._line_deg
            self.velocity_deg_s = 0.0
            self.touching = True
            self._missing = [0, 0]
            return self._state(t_s, measured=True, n=len(pts))

        assert self._fingers is not None
        pivot = int(np.argmin(self._speed))
        arc = 1 - pivot
        # predicted finger positions: pivot holds, arc finger turns about it
        pred = self._fingers.copy()
        dtheta = math.radians(self.velocity_deg_s * dt)
        c, s = math.cos(dtheta), math.sin(dtheta)
        r = pred[arc] - pred[pivot]
        pred[arc] = pred[pivot] + np.array([c * r[0] - s * r[1], s * r[0] + c * r[1]])

        x_pred = self.angle_deg + self.velocity_deg_s * dt
        if len(pts) == 0:
            seen = [False, False]
            new = pred
        else:
            new, seen = self._assign(pts, pred)

        measured = seen[arc]
        for k in (0, 1):
            self._missing[k] = 0 if seen[k] else self._missing[k] + 1
        if (
            self._missing[arc] > self.max_hold_frames
            or self._missing[pivot] > self.max_pivot_hold_frames
        ):
            self._release()
            return self._state(t_s, measured=False, n=len(pts))

        if dt > 0:
            v = np.linalg.norm(new - self._fingers, axis=1) / dt
            upd = np.array(seen, dtype=bool)
            self._speed[upd] = 0.7 * self._speed[upd] + 0.3 * v[upd]
        self._fingers = new

        if measured:
            z = self._measure(new) + self._offset_deg
            resid = z - x_pred
            self.angle_deg = x_pred + self.alpha * resid
            if dt > 0:
                self.velocity_deg_s += self.beta * resid / dt
        else:
            self.angle_deg = x_pred
            # keep the line continuous with the prediction for when the finger returns
            self._line_deg = self.angle_deg - self._offset_deg
        return self._state(t_s, measured=measured, n=len(pts))

    def _state(self, t_s: float, measured: bool, n: int) -> RotationState:
        return RotationState(
            t_s=float(t_s),
            angle_deg=float(self.angle_deg),
            velocity_deg_s=float(self.velocity_deg_s),
            touching=self.touching,
            measured=measured,
            n_contacts=n,
        )


def track(frames: Sequence[tuple[float, Sequence[Any]]], **kw: Any) -> list[RotationState]:
    """Run a fresh tracker over ``(t_s, contacts)`` frames."""
    tr = RotationTracker(**kw)
    return [tr.update(t, c) for t, c in frames]
