"""2D primitives in table millimetres -> triangles (pure numpy, no GL).

Every function returns an (N, 2) float array of triangle vertices (N a multiple of 3).
Curves use enough segments that the chord error stays under ``tol_mm``.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

TOL_MM = 0.25


def segments_for(r_mm: float, sweep_rad: float = 2 * math.pi, tol_mm: float = TOL_MM) -> int:
    """Segments for an arc of radius ``r_mm`` so the chord sagitta is below ``tol_mm``."""
    if r_mm <= tol_mm:
        return max(3, int(math.ceil(sweep_rad / (math.pi / 3))))
    step = 2.0 * math.acos(max(-1.0, 1.0 - tol_mm / r_mm))
    return int(min(512, max(8, math.ceil(sweep_rad / step))))


def rect(x: float, y: float, w: float, h: float) -> np.ndarray:
    a, b, c, d = (x, y), (x + w, y), (x + w, y + h), (x, y + h)
    return np.array([a, b, c, a, c, d], dtype=float)


def rect_outline(x: float, y: float, w: float, h: float, width_mm: float) -> np.ndarray:
    t = width_mm
    return np.concatenate(
        [
            rect(x - t / 2, y - t / 2, w + t, t),
            rect(x - t / 2, y + h - t / 2, w + t, t),
            rect(x - t / 2, y + t / 2, t, h - t),
            rect(x + w - t / 2, y + t / 2, t, h - t),
        ]
    )


@lru_cache(maxsize=512)
def _unit_arc(a0: float, a1: float, n: int) -> np.ndarray:
    t = np.linspace(a0, a1, n + 1)
    out = np.stack([np.cos(t), np.sin(t)], axis=1)
    out.flags.writeable = False
    return out


def _arc_pts(c, r: float, a0: float, a1: float, n: int) -> np.ndarray:
    return _unit_arc(float(a0), float(a1), int(n)) * r + np.asarray(c, dtype=float)


def disc(c, r_mm: float) -> np.ndarray:
    n = segments_for(r_mm)
    p = _arc_pts(c, r_mm, 0.0, 2 * math.pi, n)
    out = np.empty((3 * n, 2))
    out[0::3] = c
    out[1::3] = p[:-1]
    out[2::3] = p[1:]
    return out


def annulus_sector(c, r_in: float, r_out: float, a0_rad: float, a1_rad: float) -> np.ndarray:
    """A ring (or ring sector) between ``r_in`` and ``r_out``; angles in radians."""
    n = segments_for(r_out, abs(a1_rad - a0_rad))
    o = _arc_pts(c, r_out, a0_rad, a1_rad, n)
    i = _arc_pts(c, max(r_in, 0.0), a0_rad, a1_rad, n)
    out = np.empty((6 * n, 2))
    out[0::6], out[1::6], out[2::6] = i[:-1], o[:-1], o[1:]
    out[3::6], out[4::6], out[5::6] = i[:-1], o[1:], i[1:]
    return out


def ring(c, r_mm: float, width_mm: float) -> np.ndarray:
    return annulus_sector(c, r_mm - width_mm / 2, r_mm + width_mm / 2, 0.0, 2 * math.pi)


def polyline(pts, width_mm: float, closed: bool = False) -> np.ndarray:
    """A stroked polyline: a quad per segment and a round join/cap at each vertex."""
    p = np.asarray(pts, dtype=float).reshape(-1, 2)
    if closed and len(p) > 2:
        p = np.vstack([p, p[:1]])
    h = width_mm / 2
    a, b = p[:-1], p[1:]
    d = b - a
    n = np.hypot(d[:, 0], d[:, 1])
    keep = n > 0
    a, b, d, n = a[keep], b[keep], d[keep], n[keep]
    parts = []
    if len(a):
        o = np.stack([-d[:, 1], d[:, 0]], axis=1) / n[:, None] * h
        quads = np.stack([a + o, b + o, b - o, a + o, b - o, a - o], axis=1)
        parts.append(quads.reshape(-1, 2))
    if width_mm > 1.0:  # round joins keep thick strokes closed at corners
        for v in p if not closed else p[:-1]:
            parts.append(disc(v, h))
    return np.concatenate(parts) if parts else np.zeros((0, 2))


def signed_area(pts) -> float:
    """Shoelace area: positive for counter-clockwise in a y-up frame."""
    p = np.asarray(pts, dtype=float)
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _dedupe(p: np.ndarray) -> np.ndarray:
    keep = np.ones(len(p), bool)
    keep[1:] = np.any(np.abs(np.diff(p, axis=0)) > 1e-9, axis=1)
    p = p[keep]
    if len(p) > 1 and np.allclose(p[0], p[-1]):
        p = p[:-1]
    return p


def polygon(pts) -> np.ndarray:
    """Fill a simple (possibly concave) polygon by ear clipping, O(n^2)."""
    p = _dedupe(np.asarray(pts, dtype=float).reshape(-1, 2))
    if len(p) < 3:
        return np.zeros((0, 2))
    if signed_area(p) < 0:
        p = p[::-1]
    idx = list(range(len(p)))
    tris: list[np.ndarray] = []

    def cross(o, a, b) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    guard = 0
    while len(idx) > 3 and guard < 4 * len(p) * len(p):
        guard += 1
        n = len(idx)
        clipped = False
        for k in range(n):
            i0, i1, i2 = idx[k - 1], idx[k], idx[(k + 1) % n]
            a, b, c = p[i0], p[i1], p[i2]
            cr = cross(a, b, c)
            if cr <= 0:
                if abs(cr) < 1e-12:  # collinear: drop the middle vertex
                    del idx[k]
                    clipped = True
                    break
                continue
            inside = False
            for j in idx:
                if j in (i0, i1, i2):
                    continue
                q = p[j]
                if cross(a, b, q) >= 0 and cross(b, c, q) >= 0 and cross(c, a, q) >= 0:
                    inside = True
                    break
            if not inside:
                tris.append(np.array([a, b, c]))
                del idx[k]
                clipped = True
                break
        if not clipped:  # self-intersecting input: fall back to a fan of what is left
            break
    if len(idx) >= 3:
        rest = p[idx]
        for k in range(1, len(rest) - 1):
            tris.append(np.array([rest[0], rest[k], rest[k + 1]]))
    return np.concatenate(tris) if tris else np.zeros((0, 2))


def triangles_area(tri: np.ndarray) -> float:
    """Total (unsigned) area of a triangle list."""
    if len(tri) == 0:
        return 0.0
    a, b, c = tri[0::3], tri[1::3], tri[2::3]
    return float(
        0.5
        * np.abs(
            (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
        ).sum()
    )


def arrow(tail, head, shaft_mm: float, head_mm: float) -> np.ndarray:
    """Outline (7 points, CCW) of a block arrow from ``tail`` to ``head``."""
    t, h = np.asarray(tail, float), np.asarray(head, float)
    d = h - t
    L = float(np.hypot(*d))
    u = d / L
    n = np.array([-u[1], u[0]])
    base = h - u * min(head_mm, 0.6 * L)
    s, w = shaft_mm / 2, head_mm / 2
    return np.array(
        [t + n * s, base + n * s, base + n * w, h, base - n * w, base - n * s, t - n * s]
    )
