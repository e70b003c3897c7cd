"""Segmentation of the difference image: the high-pass image (sharp bright parts touching
the glass), the body mask (hands and forearms, including the dim parts above the glass), and
the windows of the frame where either can be non-zero, so the pipeline works on crops only
(with results equal to the whole frame's)."""

from __future__ import annotations

import cv2
import numpy as np


def highpass(diff: np.ndarray, sigma_px: float) -> np.ndarray:
    """Image minus its Gaussian blur, clipped at 0 (uint8). The blur is computed at a
    quarter of the resolution, which for sigma >= 4 px is indistinguishable and faster."""
    h, w = diff.shape
    if sigma_px >= 4:
        small = cv2.resize(diff, (w // 4, h // 4), interpolation=cv2.INTER_AREA)
        small = cv2.GaussianBlur(small, (0, 0), sigma_px / 4)
        blur = cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR)
    else:
        blur = cv2.GaussianBlur(diff, (0, 0), sigma_px)
    return cv2.subtract(diff, blur)


def frame_highpass(diff: np.ndarray, sigma_px: float) -> np.ndarray:
    """The whole frame's high-pass image as the pipeline defines it (3x3 mean first)."""
    return highpass(cv2.blur(diff, (3, 3)), sigma_px)


def _gauss_radius_px(sigma_px: float) -> int:
    """Half the kernel size ``cv2.GaussianBlur`` picks for an 8-bit image and ``sigma_px``."""
    return (int(round(sigma_px * 6 + 1)) | 1) // 2


def above_box(
    image: np.ndarray, threshold: float, within: tuple[int, int, int, int] | None = None
) -> tuple[int, int, int, int] | None:
    """``(x0, y0, x1, y1)``: the bounding box of the pixels above ``threshold`` (the test
    ``cv2.threshold`` makes), looked for in the box ``within`` only if given; None if
    there are none."""
    ox, oy = 0, 0
    if within is not None:
        ox, oy, x1, y1 = within
        image = image[oy:y1, ox:x1]
    # columns holding such a pixel, then the rows in that band (no mask image written)
    # cv2.threshold compares with floor(threshold) on 8-bit images, as do integers here
    cols = np.flatnonzero(image.max(axis=0) > threshold)
    if len(cols) == 0:
        return None
    x0, x1 = int(cols[0]), int(cols[-1]) + 1
    rows = np.flatnonzero(image[:, x0:x1].max(axis=1) > threshold)
    y0, y1 = int(rows[0]), int(rows[-1]) + 1
    return x0 + ox, y0 + oy, x1 + ox, y1 + oy


def _grow(box: tuple[int, int, int, int], by_px: int, shape: tuple[int, int]):
    x0, y0, x1, y1 = box
    return (
        max(x0 - by_px, 0),
        max(y0 - by_px, 0),
        min(x1 + by_px, shape[1]),
        min(y1 + by_px, shape[0]),
    )


def contact_window(
    diff: np.ndarray, threshold: float, within: tuple[int, int, int, int] | None = None
) -> tuple[int, int, int, int] | None:
    """``(x0, y0, x1, y1)``: the only part of the frame where ``find_contacts`` can find
    anything in the high-pass of ``cv2.blur(diff, (3, 3))`` at ``threshold``, or None
    (``within``: a box known to hold every ``diff`` pixel above ``threshold``).

    A high-pass pixel is at most its 3x3 mean, which exceeds ``threshold`` only next to
    a ``diff`` pixel that does: the box around those, grown by 1 px (the mean) and 2 px
    (the 5 px dilation that groups a contact)."""
    box = above_box(diff, threshold, within)
    return None if box is None else _grow(box, 3, diff.shape)


def body_window(
    diff: np.ndarray, threshold: float, smooth_px: int = 5
) -> tuple[np.ndarray, tuple[int, int, int, int] | None]:
    """``body_mask(diff, threshold, smooth_px)`` made only where it can be non-zero: the
    mean over ``smooth_px`` exceeds ``threshold`` only within ``smooth_px // 2`` of a
    ``diff`` pixel that does. The full-size mask, and the box that holds all of it
    (None: the mask is empty)."""
    body = np.zeros_like(diff)
    box = above_box(diff, threshold)
    if box is None:
        return body, None
    reach = smooth_px // 2 if smooth_px > 1 else 0
    x0, y0, x1, y1 = win = _grow(box, reach, diff.shape)
    cx0, cy0, cx1, cy1 = _grow(win, reach, diff.shape)  # the mean's input
    m = body_mask(diff[cy0:cy1, cx0:cx1], threshold, smooth_px)
    body[y0:y1, x0:x1] = m[y0 - cy0 : y1 - cy0, x0 - cx0 : x1 - cx0]
    return body, win


def highpass_window(
    diff: np.ndarray, sigma_px: float, window: tuple[int, int, int, int]
) -> np.ndarray:
    """``frame_highpass(diff, sigma_px)`` inside ``window`` (x0, y0, x1, y1)
    only, equal to the full-frame result there: computed on a crop wider by the reach of
    the blurs (and aligned to the 4 px blocks of the quarter-resolution blur)."""
    H, W = diff.shape
    x0, y0, x1, y1 = window
    if sigma_px >= 4:
        a, m = 4, 4 * (_gauss_radius_px(sigma_px / 4) + 2)
        if W % 4 or H % 4:  # the full frame's quarter image is not made of whole blocks
            a, m = 1, max(W, H)
    else:
        a, m = 1, _gauss_radius_px(sigma_px) + 1
    cx0, cy0 = max((x0 - m) // a * a, 0), max((y0 - m) // a * a, 0)
    cx1, cy1 = min(-(-(x1 + m) // a) * a, W), min(-(-(y1 + m) // a) * a, H)
    dx0, dy0 = max(cx0 - 1, 0), max(cy0 - 1, 0)  # the 3x3 mean reaches 1 px further
    dx1, dy1 = min(cx1 + 1, W), min(cy1 + 1, H)
    b3 = cv2.blur(diff[dy0:dy1, dx0:dx1], (3, 3))
    b3 = np.ascontiguousarray(b3[cy0 - dy0 : cy1 - dy0, cx0 - dx0 : cx1 - dx0])
    hp = highpass(b3, sigma_px)
    return hp[y0 - cy0 : y1 - cy0, x0 - cx0 : x1 - cx0]


def body_mask(diff: np.ndarray, threshold: float, smooth_px: int = 5) -> np.ndarray:
    """Hands and forearms: the smoothed difference above ``threshold`` (uint8 0/255)."""
    if smooth_px > 1:
        diff = cv2.blur(diff, (smooth_px, smooth_px))
    _, m = cv2.threshold(diff, threshold, 255, cv2.THRESH_BINARY)
    return m
