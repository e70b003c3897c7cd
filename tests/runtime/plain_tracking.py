"""The id tracker as first written, on numpy arrays (``np.hypot`` on 2-element arrays,
the Hungarian assignment for every frame): the reference the plain-float
``console.runtime.tracking.IdTracker`` is checked against."""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import linear_sum_assignment


class PlainTrack:
    def __init__(self, tid: int, pos: np.ndarray, t_s: float, angle: float) -> None:
        self.id, self.pos, self.t_s, self.angle = tid, pos, t_s, angle
        self.vel = np.zeros(2)
        self.rot_vel = self.accel = self.rot_accel = 0.0
        self.missed, self.frames = 0, 1

    @property
    def speed(self) -> float:
        return float(np.hypot(*self.vel))


class PlainIdTracker:
    def __init__(self, gate: float, grace_frames: int, alpha: float, beta: float) -> None:
        self.gate, self.grace, self.alpha, self.beta = gate, grace_frames, alpha, beta
        self.tracks: dict[int, PlainTrack] = {}
        self._next = 0

    def update(self, t_s, pts, angles) -> list[PlainTrack]:
        pts_a = np.asarray(pts, float).reshape(-1, 2)
        live = list(self.tracks.values())
        match = {}
        if live and len(pts_a):
            pred = np.array([tr.pos + tr.vel * max(t_s - tr.t_s, 0.0) for tr in live])
            d = np.hypot(*(pts_a[:, None, :] - pred[None, :, :]).transpose(2, 0, 1))
            rows, cols = linear_sum_assignment(np.where(d <= self.gate, d, 1e9))
            match = {
                int(i): live[j] for i, j in zip(rows, cols, strict=True) if d[i, j] <= self.gate
            }
        out = []
        for i, p in enumerate(pts_a):
            tr = match.get(i)
            if tr is None:
                tr = PlainTrack(self._next, p.copy(), t_s, float(angles[i]))
                self._next += 1
                self.tracks[tr.id] = tr
            else:
                dt = max(t_s - tr.t_s, 1e-6)
                speed0 = tr.speed
                pred = tr.pos + tr.vel * dt
                r = p - pred
                tr.pos = pred + self.alpha * r
                tr.vel = tr.vel + (self.beta / dt) * r
                tr.accel = (tr.speed - speed0) / dt
                rv = math.remainder(float(angles[i]) - tr.angle, 2 * math.pi) / dt
                tr.rot_accel = (rv - tr.rot_vel) / dt
                tr.angle, tr.rot_vel = float(angles[i]), rv
                tr.t_s, tr.missed, tr.frames = t_s, 0, tr.frames + 1
            out.append(tr)
        seen = {tr.id for tr in out}
        for tid, tr in list(self.tracks.items()):
            if tid not in seen:
                tr.missed += 1
                if tr.missed > self.grace:
                    del self.tracks[tid]
        return out
