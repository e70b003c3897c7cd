"""Camera <-> table mapping of the twin: a homography plus optional radial lens distortion.

The IR camera looks at the glass from below, so the image is mirrored: table x (long
edge, millimetres from the glass corner) runs right-to-left and table y bottom-to-top. The mapping
is explicit: the pixel positions of the four glass corners (undistorted) define the
homography; ``k1``/``k2`` (Brown radial model about the image centre, focal ``focal_px``)
bend it the way a wide PS3 Eye lens does. ``mm_to_px`` is what the camera sees;
``px_to_mm`` inverts it exactly (iterative undistortion, then the inverse homography).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .constants import DEFAULT_CORNERS_PX, IMAGE_PX, TABLE_MM

__all__ = ["DEFAULT_CORNERS_PX", "IMAGE_PX", "TABLE_MM", "TableMapping", "homography_4pt"]


def homography_4pt(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """The 3x3 homography taking four points ``src`` to ``dst`` (float64 solve)."""
    a = np.zeros((8, 8))
    b = np.zeros(8)
    for i, ((x, y), (u, v)) in enumerate(zip(src, dst, strict=True)):
        a[2 * i] = [x, y, 1, 0, 0, 0, -u * x, -u * y]
        a[2 * i + 1] = [0, 0, 0, x, y, 1, -v * x, -v * y]
        b[2 * i], b[2 * i + 1] = u, v
    return np.append(np.linalg.solve(a, b), 1.0).reshape(3, 3)


@dataclass(frozen=True)
class TableMapping:
    """Table millimetres <-> camera pixels. All parameters are explicit and hashable."""

    table_mm: tuple[float, float] = TABLE_MM
    image_px: tuple[int, int] = IMAGE_PX
    corners_px: tuple[tuple[float, float], ...] = DEFAULT_CORNERS_PX
    k1: float = 0.0
    k2: float = 0.0
    focal_px: float = 540.0
    _h: np.ndarray = field(init=False, repr=False, compare=False)
    _hinv: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        w, h = self.table_mm
        src = np.array([[0, 0], [w, 0], [w, h], [0, h]], dtype=np.float64)
        hm = homography_4pt(src, np.asarray(self.corners_px, dtype=np.float64))
        object.__setattr__(self, "_h", hm)
        object.__setattr__(self, "_hinv", np.linalg.inv(hm))

    @property
    def homography(self) -> np.ndarray:
        """3x3 matrix mapping table mm to undistorted pixels."""
        return self._h.copy()

    @property
    def distorted(self) -> bool:
        return self.k1 != 0.0 or self.k2 != 0.0

    @property
    def camera_matrix(self) -> np.ndarray:
        w, h = self.image_px
        return np.array(
            [[self.focal_px, 0, (w - 1) / 2], [0, self.focal_px, (h - 1) / 2], [0, 0, 1]],
            dtype=np.float64,
        )

    @property
    def dist_coeffs(self) -> np.ndarray:
        return np.array([self.k1, self.k2, 0.0, 0.0], dtype=np.float64)

    def px_per_mm(self) -> float:
        """Mean scale at the table centre (for sizing blurs and blobs)."""
        w, h = self.table_mm
        c = np.array([[w / 2, h / 2], [w / 2 + 10, h / 2], [w / 2, h / 2 + 10]])
        p = self.mm_to_px(c)
        return float((np.linalg.norm(p[1] - p[0]) + np.linalg.norm(p[2] - p[0])) / 20)

    def mm_to_px(self, pts_mm: np.ndarray) -> np.ndarray:
        """(N, 2) table mm -> (N, 2) pixels as the camera sees them."""
        p = np.asarray(pts_mm, dtype=np.float64).reshape(-1, 2)
        q = p @ self._h[:, :2].T + self._h[:, 2]
        u = q[:, :2] / q[:, 2:3]
        if not self.distorted:
            return u
        k = self.camera_matrix
        c = k[:2, 2]
        x = (u - c) / self.focal_px
        r2 = np.sum(x * x, axis=1, keepdims=True)
        return c + x * (1 + self.k1 * r2 + self.k2 * r2 * r2) * self.focal_px

    def px_to_mm(self, pts_px: np.ndarray) -> np.ndarray:
        """(N, 2) camera pixels -> (N, 2) table mm (exact inverse of ``mm_to_px``)."""
        u = np.asarray(pts_px, dtype=np.float64).reshape(-1, 2)
        if self.distorted:
            c = self.camera_matrix[:2, 2]
            xd = (u - c) / self.focal_px
            rd = np.linalg.norm(xd, axis=1)
            ru = rd.copy()
            for _ in range(30):  # Newton on ru * (1 + k1 ru^2 + k2 ru^4) = rd
                f = ru * (1 + self.k1 * ru**2 + self.k2 * ru**4) - rd
                df = 1 + 3 * self.k1 * ru**2 + 5 * self.k2 * ru**4
                step = f / np.where(np.abs(df) < 1e-9, 1e-9, df)
                ru -= step
                if np.max(np.abs(step)) < 1e-13:
                    break
            scale = np.divide(ru, rd, out=np.ones_like(rd), where=rd > 0)
            u = c + xd * scale[:, None] * self.focal_px
        q = u @ self._hinv[:, :2].T + self._hinv[:, 2]
        return q[:, :2] / q[:, 2:3]

    def table_polygon_px(self, n_per_edge: int = 16) -> np.ndarray:
        """Outline of the glass in pixels (curved edges when distorted)."""
        w, h = self.table_mm
        t = np.linspace(0, 1, n_per_edge, endpoint=False)
        edges = [
            np.c_[t * w, 0 * t],
            np.c_[w + 0 * t, t * h],
            np.c_[(1 - t) * w, h + 0 * t],
            np.c_[0 * t, (1 - t) * h],
        ]
        return self.mm_to_px(np.vstack(edges))

    def to_dict(self) -> dict:
        return {
            "table_mm": list(self.table_mm),
            "image_px": list(self.image_px),
            "corners_px": [list(c) for c in self.corners_px],
            "k1": self.k1,
            "k2": self.k2,
            "focal_px": self.focal_px,
        }
