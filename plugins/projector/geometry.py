"""Projector geometry: table millimetres -> projector pixels through a homography.

The calibration is a set of point pairs (table mm, projector px) that the operator
adjusts, usually the four glass corners; the homography is fitted from them with the
normalised DLT (Hartley). It is stored as JSON in the profile's state directory
(``settings.calibration_path_for``). Pixel y points down, (0, 0) is the top-left pixel
corner of the projector frame.
"""

from __future__ import annotations

import contextlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from console.plugin_api import UserError

#: 3M SCT-3250 glass (paper, section 2); used when no profile gives [table].
GLASS_MM: tuple[float, float] = (743.46, 447.29)
CALIBRATION_VERSION = 1


def glass_corners_mm(table_mm: tuple[float, float] = GLASS_MM) -> np.ndarray:
    """The four glass corners in order 1..4: (0,0), (W,0), (W,H), (0,H)."""
    w, h = table_mm
    return np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]])


def frame_corners_px(frame_px: tuple[int, int]) -> np.ndarray:
    """The projector frame corners in the same order as ``glass_corners_mm``."""
    w, h = frame_px
    return np.array([[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]], dtype=float)


def _normaliser(p: np.ndarray) -> np.ndarray:
    """Similarity moving the centroid to 0 and the mean distance to sqrt(2) (Hartley)."""
    c = p.mean(axis=0)
    d = np.sqrt(((p - c) ** 2).sum(axis=1)).mean()
    s = math.sqrt(2.0) / d if d > 0 else 1.0
    return np.array([[s, 0.0, -s * c[0]], [0.0, s, -s * c[1]], [0.0, 0.0, 1.0]])


def _three_collinear(p: np.ndarray, rel_tol: float = 1e-6) -> bool:
    """Whether any three of the points lie on a line (area tiny against the spread)."""
    scale = float(np.ptp(p, axis=0).max()) or 1.0
    for i in range(len(p)):
        for j in range(i + 1, len(p)):
            for k in range(j + 1, len(p)):
                a, b, c = p[i], p[j], p[k]
                area2 = abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
                if area2 <= rel_tol * scale * scale:
                    return True
    return False


def fit_homography(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """Homography H (3x3, H[2,2] = 1) with dst ~ H src, least squares over 4+ pairs.

    Raises ``UserError`` for fewer than four pairs or a degenerate set (three of four
    points on a line, all points on a line), which has no unique homography.
    """
    src = np.asarray(src, dtype=float).reshape(-1, 2)
    dst = np.asarray(dst, dtype=float).reshape(-1, 2)
    n = len(src)
    if n < 4 or len(dst) != n:
        raise UserError(
            f"projector calibration: {n} point pairs; give at least 4 (the glass corners)"
        )
    if n == 4 and (_three_collinear(src) or _three_collinear(dst)):
        raise UserError(
            "projector calibration: the points are degenerate (three of the four on a line); "
            "use four points near the glass corners"
        )
    ts, td = _normaliser(src), _normaliser(dst)
    s = (ts @ np.c_[src, np.ones(n)].T).T
    d = (td @ np.c_[dst, np.ones(n)].T).T
    a = np.zeros((2 * n, 9))
    for i in range(n):
        x, y, _ = s[i]
        u, v, _ = d[i]
        a[2 * i] = [-x, -y, -1, 0, 0, 0, u * x, u * y, u]
        a[2 * i + 1] = [0, 0, 0, -x, -y, -1, v * x, v * y, v]
    _, sv, vt = np.linalg.svd(a)
    # A unique solution needs rank 8: the 8th singular value must stand clear of zero.
    if sv[7] < 1e-8 * sv[0]:
        raise UserError(
            "projector calibration: the points are degenerate (three or more on a line); "
            "use four points near the glass corners"
        )
    hn = vt[-1].reshape(3, 3)
    h = np.linalg.inv(td) @ hn @ ts
    if abs(h[2, 2]) < 1e-12 or abs(np.linalg.det(hn)) < 1e-9:
        raise UserError(
            "projector calibration: the points are degenerate (the mapping is singular); "
            "re-enter four points near the glass corners"
        )
    return h / h[2, 2]


def apply(h: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Map (N, 2) points through homography ``h``."""
    p = np.asarray(pts, dtype=float).reshape(-1, 2)
    q = np.c_[p, np.ones(len(p))] @ np.asarray(h, dtype=float).T
    return q[:, :2] / q[:, 2:3]


def _convex_same_orientation(quad: np.ndarray) -> bool:
    z = []
    for i in range(4):
        a, b, c = quad[i], quad[(i + 1) % 4], quad[(i + 2) % 4]
        z.append((b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]))
    return all(v > 0 for v in z) or all(v < 0 for v in z)


@dataclass
class Calibration:
    """Table mm -> projector px for a frame of ``frame_px`` pixels."""

    frame_px: tuple[int, int]
    points_mm: list[tuple[float, float]]
    points_px: list[tuple[float, float]]
    table_mm: tuple[float, float] = GLASS_MM
    h: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.frame_px = (int(self.frame_px[0]), int(self.frame_px[1]))
        self.h = fit_homography(np.array(self.points_mm), np.array(self.points_px))
        corners = apply(self.h, glass_corners_mm(self.table_mm))
        w = self.w_at(glass_corners_mm(self.table_mm))
        if not (np.all(w > 0) or np.all(w < 0)) or not _convex_same_orientation(corners):
            raise UserError(
                "projector calibration: the glass would be folded or flipped through the "
                "horizon; check the order of the corner points (1 (0,0), 2 (W,0), 3 (W,H), 4 (0,H))"
            )
        if np.all(w < 0):  # same mapping, positive w over the glass (clip space needs it)
            self.h = -self.h

    def w_at(self, pts_mm: np.ndarray) -> np.ndarray:
        p = np.asarray(pts_mm, dtype=float).reshape(-1, 2)
        return np.c_[p, np.ones(len(p))] @ self.h[2]

    def h_for(self, size_px: tuple[int, int]) -> np.ndarray:
        """The homography for a render target of ``size_px`` (scaled from the frame)."""
        sx = size_px[0] / self.frame_px[0]
        sy = size_px[1] / self.frame_px[1]
        return np.diag([sx, sy, 1.0]) @ self.h

    def to_px(self, pts_mm: np.ndarray, size_px: tuple[int, int] | None = None) -> np.ndarray:
        return apply(self.h if size_px is None else self.h_for(size_px), pts_mm)

    def mm_per_px(self) -> float:
        """Mean table millimetres per projector pixel over the glass (for sizing text)."""
        c = apply(self.h, glass_corners_mm(self.table_mm))
        x = 0.5 * (np.linalg.norm(c[1] - c[0]) + np.linalg.norm(c[2] - c[3]))
        return self.table_mm[0] / x

    def with_point(self, mm: tuple[float, float], px: tuple[float, float]) -> Calibration:
        """A copy with the pair at ``mm`` replaced (or added): the operator's adjustment."""
        pts_mm = [tuple(p) for p in self.points_mm]
        pts_px = [tuple(p) for p in self.points_px]
        for i, p in enumerate(pts_mm):
            if math.dist(p, mm) < 1e-6:
                pts_px[i] = (float(px[0]), float(px[1]))
                break
        else:
            pts_mm.append((float(mm[0]), float(mm[1])))
            pts_px.append((float(px[0]), float(px[1])))
        return Calibration(self.frame_px, pts_mm, pts_px, self.table_mm)

    def residuals_px(self) -> np.ndarray:
        """Distance between each operator point and where the fitted homography puts it."""
        return np.linalg.norm(apply(self.h, self.points_mm) - np.array(self.points_px), axis=1)

    def to_json(self) -> dict:
        return {
            "version": CALIBRATION_VERSION,
            "frame_px": list(self.frame_px),
            "table_mm": list(self.table_mm),
            "points": [
                {"mm": list(m), "px": list(p)}
                for m, p in zip(self.points_mm, self.points_px, strict=True)
            ],
            "H_mm_to_px": self.h.tolist(),
        }

    @classmethod
    def from_json(cls, data: dict, where: str = "calibration") -> Calibration:
        try:
            pts = data["points"]
            return cls(
                frame_px=tuple(data["frame_px"]),
                points_mm=[tuple(map(float, p["mm"])) for p in pts],
                points_px=[tuple(map(float, p["px"])) for p in pts],
                table_mm=tuple(data.get("table_mm", GLASS_MM)),
            )
        except (KeyError, TypeError, ValueError) as e:
            raise UserError(
                f"{where}: not a projector calibration ({e}); delete it or run "
                "`haptable projector --reset-calibration`"
            ) from None


def default_calibration(
    frame_px: tuple[int, int], table_mm: tuple[float, float] = GLASS_MM
) -> Calibration:
    """The glass corners on the projector frame corners (x right, y down)."""
    return Calibration(
        frame_px,
        [tuple(p) for p in glass_corners_mm(table_mm)],
        [tuple(p) for p in frame_corners_px(frame_px)],
        table_mm,
    )


def load_calibration(
    path: Path | None, frame_px: tuple[int, int], table_mm: tuple[float, float] = GLASS_MM
) -> Calibration:
    """The stored calibration at ``path``, or the default when there is none."""
    if path is None or not Path(path).exists():
        return default_calibration(frame_px, table_mm)
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as e:
        raise UserError(
            f"{path}: cannot read the projector calibration ({e}); fix or delete it"
        ) from None
    return Calibration.from_json(data, str(path))


def save_calibration(cal: Calibration, path: Path) -> None:
    """Write ``cal`` as JSON (atomically, so a crash never leaves half a file)."""
    path = Path(path)
    tmp = path.with_suffix(path.suffix + ".tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp.write_text(json.dumps(cal.to_json(), indent=2) + "\n", encoding="utf-8")
        tmp.replace(path)
    except OSError as exc:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        raise UserError(
            f"{path}: cannot write the projector calibration ({exc.strerror or exc}); give a "
            "writable file ([projector] calibration_path) or leave it empty for the state "
            "directory"
        ) from None
