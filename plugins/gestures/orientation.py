"""How the camera is mounted, and which part of its view counts: the image turned by
``rotate_deg`` (0/90/180/270, clockwise), then mirrored left-right (``mirror``), then
everything outside the region of interest (margins in px of the turned image) made equal
to the background, so segmentation finds nothing there.

``Orientation.apply(image)`` turns a camera image; ``undo(image)`` turns one back (a
mask of the turned image onto the camera's pixels, for the background's update).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from console.plugin_api import UserError

_ROTATE = {90: cv2.ROTATE_90_CLOCKWISE, 180: cv2.ROTATE_180, 270: cv2.ROTATE_90_COUNTERCLOCKWISE}
_UNROTATE = {90: cv2.ROTATE_90_COUNTERCLOCKWISE, 180: cv2.ROTATE_180, 270: cv2.ROTATE_90_CLOCKWISE}


@dataclass(frozen=True)
class Orientation:
    """``rotate_deg`` clockwise, then ``mirror``; ROI margins (left, top, right, bottom)
    in px of the turned image (0: none)."""

    rotate_deg: int = 0
    mirror: bool = False
    margins_px: tuple[int, int, int, int] = (0, 0, 0, 0)

    def __post_init__(self) -> None:
        if self.rotate_deg not in (0, 90, 180, 270):
            raise UserError(
                f"[vision] rotate_deg = {self.rotate_deg}: the camera turns by 0, 90, 180 or 270"
            )
        if min(self.margins_px) < 0:
            raise UserError(f"[vision] roi margins {self.margins_px}: a margin is 0 px or more")

    @property
    def turns(self) -> bool:
        return self.rotate_deg != 0 or self.mirror

    @property
    def crops(self) -> bool:
        return any(self.margins_px)

    @property
    def identity(self) -> bool:
        return not (self.turns or self.crops)

    def shape(self, camera_shape: tuple[int, int]) -> tuple[int, int]:
        """(rows, cols) of a turned ``camera_shape`` image."""
        h, w = camera_shape
        return (w, h) if self.rotate_deg in (90, 270) else (h, w)

    def apply(self, image: np.ndarray) -> np.ndarray:
        """``image`` turned (a view or copy; the input is never changed)."""
        out = image
        if self.rotate_deg:
            out = cv2.rotate(out, _ROTATE[self.rotate_deg])
        if self.mirror:
            out = cv2.flip(out, 1)
        return out

    def undo(self, image: np.ndarray) -> np.ndarray:
        """A turned image back in the camera's orientation (``apply``'s inverse)."""
        out = image
        if self.mirror:
            out = cv2.flip(out, 1)
        if self.rotate_deg:
            out = cv2.rotate(out, _UNROTATE[self.rotate_deg])
        return out

    def roi(self, shape: tuple[int, int]) -> tuple[int, int, int, int]:
        """(x0, y0, x1, y1) of the region of interest in a turned image of ``shape``
        (never empty: margins that leave nothing leave one pixel)."""
        h, w = shape
        left, top, right, bottom = self.margins_px
        x0, y0 = min(left, w - 1), min(top, h - 1)
        return x0, y0, max(x0 + 1, w - right), max(y0 + 1, h - bottom)

    def outside_as(self, image: np.ndarray, background: np.ndarray) -> np.ndarray:
        """``image`` with every pixel outside the ROI taken from ``background`` (both
        turned): no difference there, so no hand and no contact."""
        if not self.crops:
            return image
        x0, y0, x1, y1 = self.roi(image.shape)
        out = background.copy()
        out[y0:y1, x0:x1] = image[y0:y1, x0:x1]
        return out
