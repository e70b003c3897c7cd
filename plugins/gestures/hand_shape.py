"""Hand geometry from one hand's mask: palm centre and radius, the wrist arc (where the
forearm leaves the hand), the canonical pose (wrist turned to the image bottom) and its
silhouette and the number of extended fingers."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np

if TYPE_CHECKING:
    from .vision import VisionParams

GRID_SECTORS = 8
GRID_RINGS = (0.0, 1.3, 2.3, 4.0)  # palm radii


def palm(mask: np.ndarray) -> tuple[tuple[float, float], float]:
    """Palm centre and radius: the maximum of the distance transform inside ``mask``."""
    if cv2.countNonZero(mask) == mask.size:  # no edge inside: the image's border is it
        mask = cv2.copyMakeBorder(mask, 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=0)
        d = cv2.distanceTransform(mask, cv2.DIST_L2, 3)[1:-1, 1:-1]
    else:
        d = cv2.distanceTransform(mask, cv2.DIST_L2, 3)
    _, r, _, loc = cv2.minMaxLoc(d)
    return (float(loc[0]), float(loc[1])), float(r)


def _runs(on: np.ndarray) -> list[tuple[int, int]]:
    """Circular runs of True in ``on``: (start index, length), in index order."""
    n = len(on)
    prev = np.concatenate((on[-1:], on[:-1]))  # on shifted round by one
    starts = np.flatnonzero(on > prev).tolist()  # on, and off before
    if not starts:
        return [(0, n)] if on[0] else []
    ends = np.flatnonzero(on < prev).tolist()  # off, and on before: one past a run
    if ends[0] < starts[0]:  # the first run wraps round from the end
        ends = ends[1:] + ends[:1]
    return [(s, (e - s) % n) for s, e in zip(starts, ends, strict=True)]


@functools.cache
def _disk(radius_px: int) -> np.ndarray:
    """Elliptic structuring element of ``2 radius + 1`` px (read-only)."""
    d = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius_px + 1, 2 * radius_px + 1))
    d.flags.writeable = False
    return d


@functools.cache
def _circle(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Angles of ``n`` points equally spaced on a circle, their cosines and sines."""
    a = np.arange(n) * (2 * math.pi / n)
    for v in (a, c := np.cos(a), s := np.sin(a)):
        v.flags.writeable = False
    return a, c, s


@functools.cache
def _wrist_sector(n: int) -> np.ndarray:
    """Which of ``_circle(n)``'s angles are within 60 degrees of straight down (+y)."""
    a = _circle(n)[0]
    down = np.abs(((a - math.pi / 2) + math.pi) % (2 * math.pi) - math.pi) < math.radians(60)
    down.flags.writeable = False
    return down


def circle_samples(
    mask: np.ndarray,
    center: tuple[float, float],
    radius: float,
    n: int = 180,
    offset: tuple[int, int] = (0, 0),
    image_shape: tuple[int, int] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Angles (rad, image axes: x right, y down), on-mask and outside-image flags of ``n``
    points on a circle. ``mask`` may be a crop of the image at ``offset`` (x, y) of an
    image of ``image_shape`` (default: the mask is the whole image)."""
    a, cos_a, sin_a = _circle(n)
    x = np.rint(center[0] + radius * cos_a).astype(np.intp)
    y = np.rint(center[1] + radius * sin_a).astype(np.intp)
    h, w = mask.shape
    ih, iw = image_shape or (h, w)
    # negative coordinates wrap round to huge unsigned ones: one test per axis
    inside = (x.view(np.uintp) < w) & (y.view(np.uintp) < h)
    if offset == (0, 0) and (ih, iw) == (h, w):
        out = ~inside
    else:
        out = ((x + offset[0]).view(np.uintp) >= iw) | ((y + offset[1]).view(np.uintp) >= ih)
    on = np.zeros(n, dtype=bool)
    on[inside] = mask[y[inside], x[inside]] > 0
    return a, on, out


def bright_centroid(mask: np.ndarray, diff: np.ndarray) -> tuple[float, float] | None:
    """Centroid of a hand weighted by brightness squared: where it presses on the glass
    (steadier than the palm centre, which may jump along a forearm)."""
    d = cv2.bitwise_and(diff, diff, mask=mask)  # 0 off the hand
    m1 = cv2.moments(cv2.multiply(d, d, dtype=cv2.CV_32F))
    if m1["m00"] <= 0:
        return None
    return m1["m10"] / m1["m00"], m1["m01"] / m1["m00"]


def mask_moments(mask: np.ndarray) -> tuple[float, float, float]:
    """``m00``, ``m10`` and ``m01`` of a 0/255 mask, those of ``cv2.moments(mask,
    binaryImage=True)`` (whole numbers: exact either way), from its column and row sums,
    for a fifth of the cost."""
    cols = cv2.reduce(mask, 0, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel()
    rows = cv2.reduce(mask, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S).ravel()
    m10 = int(cols @ np.arange(len(cols)))
    return int(cols.sum()) / 255, m10 / 255, int(rows @ np.arange(len(rows))) / 255


def brightness_axis(
    mask: np.ndarray,
    diff: np.ndarray,
    min_shift_px: float = 1.0,
    bright: tuple[float, float] | None = None,
) -> float | None:
    """Direction (rad) from the brightness-weighted centroid of a hand (``mask``: 0/255)
    to its plain centroid: towards the dimmer forearm. None if the two nearly coincide."""
    m00, m10, m01 = mask_moments(mask)
    if m00 <= 0:
        return None
    b = bright if bright is not None else bright_centroid(mask, diff)
    if b is None:
        return None
    dx = m10 / m00 - b[0]
    dy = m01 / m00 - b[1]
    if math.hypot(dx, dy) < min_shift_px:
        return None
    return math.atan2(dy, dx)


@dataclass(frozen=True)
class WristArc:
    """Where the forearm leaves the hand: arc on a circle about the palm (radians)."""

    start_rad: float
    width_rad: float
    found: str  # "forearm", "border" (forearm leaving the image), "fallback"
    direction_rad: float  # the forearm direction from the palm centre

    @property
    def mid_rad(self) -> float:
        """Midpoint of the arc (the forearm direction if no arc was found)."""
        if self.width_rad <= 0 or self.width_rad > 2 * math.pi / 3:
            return self.direction_rad
        return self.start_rad + 0.5 * self.width_rad


def _cell_means(mask: np.ndarray, k: int) -> np.ndarray:
    """The means of ``mask``'s k x k px cells, the mask padded with zeros (no hand) to
    whole cells: each cell is exactly k px, so cell (i, j)'s centre is pixel
    ((j + 0.5) k - 0.5, (i + 0.5) k - 0.5), and ``INTER_AREA`` takes its integer-scale
    path (a fractional scale costs about 40 us more a hand)."""
    if k == 1:
        return mask
    h, w = mask.shape
    ph, pw = -h % k, -w % k
    if ph or pw:
        mask = cv2.copyMakeBorder(mask, 0, ph, 0, pw, cv2.BORDER_CONSTANT, value=0)
    return cv2.resize(mask, ((w + pw) // k, (h + ph) // k), interpolation=cv2.INTER_AREA)


def wrist_arc(
    mask: np.ndarray,
    center: tuple[float, float],
    palm_radius: float,
    params: VisionParams,
    contour: np.ndarray | None = None,
    offset: tuple[int, int] = (0, 0),
    image_shape: tuple[int, int] | None = None,
    hint_rad: float | None = None,
) -> WristArc:
    """The arc where the forearm crosses a circle of ``wrist_radius`` palm radii about the
    palm centre (``mask`` is this hand's mask, ``center`` in its coordinates).

    The forearm is the thick part reaching farthest from the palm: the mask opened with
    a disk of ``finger_width`` palm radii (fingers vanish, palm and forearm stay), and
    the opened pixel farthest from the palm gives its direction (a forearm fading with
    height, or leaving the image, is still longer than any finger group). The arc is the
    run of the circle (on the mask or off the image) around that direction. With no
    thick part beyond the circle (a fingertip alone, a fist), the direction opposite the
    contour point farthest from the palm (fingers point away from the wrist).

    ``hint_rad`` (from ``brightness_axis``: the forearm is higher above the glass, hence
    dimmer, than the hand) settles the sign: a direction more than 90 degrees from the
    hint is turned round; with no direction found, the hint is used.
    """
    r = params.wrist_radius * palm_radius
    h, w = mask.shape
    k = 4 if palm_radius >= 12 else 1
    _, small = cv2.threshold(_cell_means(mask, k), 127, 255, cv2.THRESH_BINARY)
    rad = max(int(round(params.finger_width * palm_radius / k)), 1)
    opened = cv2.morphologyEx(small, cv2.MORPH_OPEN, _disk(rad))
    ys, xs = np.nonzero(opened)
    direction: float | None = None
    found = "fallback"
    if len(xs):
        px = (xs + 0.5) * k - 0.5
        py = (ys + 0.5) * k - 0.5
        dx, dy = px - center[0], py - center[1]
        d2 = dx * dx + dy * dy
        i = int(np.argmax(d2))
        ih, iw = image_shape or (h, w)
        sh, sw = opened.shape
        edge = None
        # pixel centres span offset + (0.5 k - 0.5) .. offset + (size - 0.5) k - 0.5:
        # look for pixels at the image edge only if that span reaches it
        lo_x, lo_y = offset[0] + 0.5 * k - 0.5, offset[1] + 0.5 * k - 0.5
        if (
            min(lo_x, lo_y) < k + 1
            or lo_x + (sw - 1) * k > iw - k - 2
            or lo_y + (sh - 1) * k > ih - k - 2
        ):
            gx, gy = px + offset[0], py + offset[1]
            edge = (gx < k + 1) | (gy < k + 1) | (gx > iw - k - 2) | (gy > ih - k - 2)
            if not edge.any():
                edge = None
        if edge is not None:  # the thick part leaves the image: the forearm goes that way
            direction = math.atan2(float(dy[edge].mean()), float(dx[edge].mean()))
            found = "border"
        elif d2[i] > r * r:
            # mean direction of the thick pixels beyond the circle near the farthest one
            far = math.atan2(dy[i], dx[i])
            beyond = d2 > r * r
            ang = np.arctan2(dy[beyond], dx[beyond])
            ang = ang[np.cos(ang - far) > math.cos(math.radians(35))]
            direction = math.atan2(float(np.sin(ang).sum()), float(np.cos(ang).sum()))
            found = "forearm"
    if hint_rad is not None:
        if direction is None:
            direction, found = hint_rad, "brightness"
        elif math.cos(direction - hint_rad) < 0:
            direction += math.pi
    if direction is None:
        if contour is not None and len(contour):
            d = contour - np.asarray(center)
            far = d[np.argmax(np.hypot(d[:, 0], d[:, 1]))]
            direction = math.atan2(-far[1], -far[0])
        else:
            direction = math.pi / 2
    n = 180
    a, on, out = circle_samples(mask, center, r, n, offset, image_shape)
    dang = 2 * math.pi / n
    j = int(round((direction % (2 * math.pi)) / dang)) % n
    for s0, length in _runs(on | out):
        if (j - s0) % n < length:
            return WristArc(float(a[s0]), float(length * dang), found, direction)
    return WristArc(direction, 0.0, found, direction)


def canonical_angle_deg(wrist_mid_rad: float) -> float:
    """Counter-clockwise rotation (degrees, as the image is displayed, for
    ``cv2.getRotationMatrix2D``) that brings the wrist direction to straight down (the
    reference edge at the image bottom)."""
    # cv2 positive angle = counter-clockwise on screen = clockwise in (x right, y down) math
    # a point at image angle phi (y down) moves to phi - angle.
    deg = math.degrees(wrist_mid_rad) - 90.0
    return (deg + 180.0) % 360.0 - 180.0


def canonical_silhouette(
    mask: np.ndarray,
    center: tuple[float, float],
    palm_radius: float,
    angle_deg: float,
    params: VisionParams,
    outline: np.ndarray | None = None,
) -> np.ndarray | None:
    """The hand rotated about the palm centre so the wrist points down, forearm cut off
    ``wrist_cut`` palm radii below the centre: its largest outer contour (N, 2) float in
    a frame whose origin is the palm centre. None if nothing is left. ``outline``: points
    (N, 2) in ``mask``'s pixels whose box holds every pixel of the mask (its contour),
    to rotate less of the square (default: the mask's corners)."""
    h, w = mask.shape
    corners = np.array([[0, 0], [w, 0], [0, h], [w, h]], np.float64) - np.asarray(center)
    half = int(math.ceil(float(np.hypot(corners[:, 0], corners[:, 1]).max()))) + 2
    size = 2 * half + 1
    m = cv2.getRotationMatrix2D((float(center[0]), float(center[1])), angle_deg, 1.0)
    m[0, 2] += half - center[0]
    m[1, 2] += half - center[1]
    cut = int(round(half + params.wrist_cut * palm_radius))
    if cut <= 0:
        return None
    # where the mask's pixels land: a set pixel is within 1 px of its source's image,
    # which is inside the outline's, so 3 px more each side holds every pixel set
    if outline is None:
        outline = np.array([[0, 0], [w - 1, 0], [0, h - 1], [w - 1, h - 1]], np.float64)
    at = cv2.transform(np.asarray(outline, np.float64).reshape(-1, 1, 2), m)
    bx, by, bw, bh = cv2.boundingRect(at.astype(np.float32))
    x0, y0 = max(bx - 3, 0), max(by - 3, 0)
    x1, y1 = min(bx + bw + 3, size), min(by + bh + 3, size, cut)
    if y1 <= y0 or x1 <= x0:
        return None
    # only the square's top left up to that box's far edges is made (each output pixel
    # depends on its own position alone, so they are those pixels of the whole rotated
    # square), and its outline looked for in that box alone (all else is 0)
    rot = cv2.warpAffine(mask, m, (x1, y1), flags=cv2.INTER_NEAREST)
    contours, _ = cv2.findContours(
        rot[y0:, x0:], cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE, offset=(x0, y0)
    )
    if not contours:
        return None
    c = max(contours, key=cv2.contourArea)
    return c.reshape(-1, 2).astype(np.float64) - half


def count_fingers(silhouette: np.ndarray, palm_radius: float, params: VisionParams) -> int:
    """Extended fingers of a canonical silhouette (wrist down, palm centre at origin):
    how wide the silhouette is where it crosses a circle of ``finger_radius`` palm radii,
    excluding the wrist sector, in finger widths."""
    if silhouette is None or len(silhouette) < 3 or palm_radius <= 0:
        return 0
    r = params.finger_radius * palm_radius
    half = int(math.ceil(np.abs(silhouette).max())) + 2
    poly = np.rint(silhouette + half).astype(np.int32)
    # the filled silhouette in a square of side 2 half + 1 about the palm centre, made
    # only as far right and down as the polygon reaches (beyond it all is off)
    m = np.zeros((int(poly[:, 1].max()) + 1, int(poly[:, 0].max()) + 1), np.uint8)
    cv2.fillPoly(m, [poly], 255)
    _, on, _ = circle_samples(m, (half, half), r, 180)
    on &= ~_wrist_sector(180)
    count = 0
    dang = 2 * math.pi / 180
    width = params.finger_width * palm_radius
    for _, length in _runs(on):
        chord = length * dang * r
        if chord < 0.25 * width:
            continue
        count += max(1, int(round(chord / width)))
    return min(count, 5)


def to_canonical(
    pts_px: np.ndarray, center: tuple[float, float], angle_deg: float, scale: float = 1.0
) -> np.ndarray:
    """Image points -> the canonical hand frame (palm centre at 0, wrist towards +y),
    divided by ``scale`` (e.g. the palm radius)."""
    p = np.asarray(pts_px, dtype=np.float64).reshape(-1, 2)
    out = np.empty((len(p), 2))
    out[:, 0], out[:, 1] = _canonical_xy(p[:, 0], p[:, 1], center, angle_deg, scale)
    return out


def _canonical_xy(
    x: np.ndarray, y: np.ndarray, center: tuple[float, float], angle_deg: float, scale: float
) -> tuple[np.ndarray, np.ndarray]:
    """``to_canonical`` on coordinate arrays: (u, v) arrays."""
    t = math.radians(angle_deg)
    dx, dy = x - center[0], y - center[1]
    c, s_ = math.cos(t), math.sin(t)
    return (dx * c + dy * s_) / scale, (-dx * s_ + dy * c) / scale
