"""Rear-DI vision pipeline: background, subtraction, high-pass, hands, wrist, canonical
pose, descriptors, finger count and contact points. Pure functions of arrays (numpy +
OpenCV 5) plus one small stateful background model.

Steps for one frame (paper section 3, Fig. 4):

1. ``check_frame``: 2-D uint8 of the expected size, else a ``UserError``.
2. ``subtract``: frame minus the background, after matching the global brightness
   (a sudden illumination change is a gain and an offset on the whole frame: a robust
   line fit of frame against background over a pixel grid estimates them; the hands
   cover a minority of the pixels and are left out as the brighter residuals).
3. ``body_mask``: smoothed difference above ``body_threshold``: hands and forearms,
   including the dim, blurred parts above the glass.
4. ``highpass`` (difference minus its blur) above ``contact_threshold``: the sharp bright
   parts touching the glass -> contact blobs. Both thresholds rise with the noise
   measured in step 2.
5. per body component: palm centre (maximum of the distance transform), the forearm
   direction (the thick part reaching farthest, or leaving the image; its sign checked
   against the brightness axis, as the forearm is higher above the glass and dimmer),
   the wrist arc where it crosses a circle about the palm, the angle that turns the
   wrist to the reference edge (image bottom), the hand rotated about the centre, the
   wrist and forearm cut off, the smallest enclosing circle, Fourier descriptors of the
   canonical silhouette, the number of extended fingers, and a brightness grid in the
   canonical frame (which parts press on the glass).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field

import cv2
import numpy as np

from console.errors import UserError
from console.types import Contact, Hand

from .descriptors import fourier_descriptors

GRID_SECTORS = 8
GRID_RINGS = (0.0, 1.3, 2.3, 4.0)  # palm radii


@dataclass(frozen=True)
class VisionParams:
    """Pipeline settings (profile section ``[vision]``)."""

    width_px: int = 640
    height_px: int = 480
    body_threshold: float = 14.0  # grey levels above background
    contact_threshold: float = 30.0  # grey levels of the high-pass image
    highpass_sigma_px: float = 6.0
    smooth_px: int = 5
    min_hand_area_px: int = 600
    # a blob over this fraction of the frame is no hand (a hand is ~5 % of the table's
    # view) but a blinded, covered or saturated camera
    max_hand_fraction: float = 0.5
    min_contact_area_px: int = 3
    max_contact_area_px: int = 2500
    max_contact_size_px: int = 45
    wrist_radius: float = 1.6  # circle about the palm where the forearm is looked for, palm radii
    wrist_cut: float = 1.15  # canonical silhouette cut this many palm radii below the palm centre
    finger_radius: float = 1.75  # circle where extended fingers are counted, palm radii
    finger_width: float = 0.55  # one finger's width, palm radii
    n_harmonics: int = 12
    rotation_invariant: bool = True
    illumination_tolerance: float = 0.15  # |gain - 1| above this flags an illumination change
    offset_tolerance: float = 8.0  # |offset| grey levels above this flags one too

    @property
    def shape(self) -> tuple[int, int]:
        return (self.height_px, self.width_px)


@dataclass(frozen=True)
class FrameResult:
    """What the pipeline found in one frame."""

    hands: tuple[Hand, ...]
    contacts: tuple[Contact, ...]  # all contact blobs, hands or not
    gain: float = 1.0  # frame ~ gain * background + offset
    offset: float = 0.0
    noise: float = 0.0  # robust std of the difference image (grey levels)
    illumination_changed: bool = False
    #: "diff", "body", "highpass" (computed on first access) with ``keep_masks``
    masks: Mapping[str, np.ndarray] = field(default_factory=dict, compare=False, repr=False)
    #: per hand (same order as ``hands``): palm_radius_px, palm_px, bright_px (the
    #: brightness-weighted centroid), grid (brightness in the canonical frame,
    #: ``GRID_SECTORS`` x rings), contacts_canon ((k, 2) in palm radii)
    extras: tuple[dict, ...] = field(default=(), compare=False, repr=False)

    def view(self, name: str) -> np.ndarray | None:
        """The intermediate image ``name`` (``diff``, ``body``, ``highpass``), or ``None``
        when this result kept none (``console.contracts.VisionResult``)."""
        return self.masks.get(name)


class Masks(Mapping):
    """A frame's intermediate images: given ones, and ones made on first access from a
    function of no arguments (the full-frame high-pass, which the pipeline itself needs
    only near the contacts)."""

    def __init__(self, images: dict[str, np.ndarray], makers: dict[str, Callable]) -> None:
        self._images = dict(images)
        self._makers = dict(makers)

    def __getitem__(self, key: str) -> np.ndarray:
        if key not in self._images:
            self._images[key] = self._makers[key]()  # KeyError if neither
        return self._images[key]

    def __iter__(self) -> Iterator[str]:
        return iter([*self._images, *(k for k in self._makers if k not in self._images)])

    def __len__(self) -> int:
        return sum(1 for _ in self)


# --------------------------------------------------------------------------- input
def check_frame(image: object, shape: tuple[int, int] | None = (480, 640)) -> np.ndarray:
    """The frame as a 2-D uint8 array; a ``UserError`` naming what is wrong otherwise."""
    if not isinstance(image, np.ndarray):
        raise UserError(
            f"camera frame: got {type(image).__name__}, not an image array; "
            "pass a 2-D uint8 numpy array"
        )
    if image.ndim == 3 and image.shape[2] == 1:
        image = image[:, :, 0]
    if image.ndim != 2:
        raise UserError(
            f"camera frame: shape {image.shape} is not a grayscale image; "
            "convert to 8-bit grayscale (cv2.cvtColor(..., cv2.COLOR_BGR2GRAY))"
        )
    if image.dtype != np.uint8:
        raise UserError(
            f"camera frame: dtype {image.dtype} is not uint8; "
            "use 8-bit grayscale frames (scale and convert with np.clip(...).astype(np.uint8))"
        )
    if shape is not None and image.shape != tuple(shape):
        raise UserError(
            f"camera frame: size {image.shape[1]} x {image.shape[0]} px does not match "
            f"[vision] width_px x height_px = {shape[1]} x {shape[0]}; "
            "set the profile to the camera's size or resize the frames"
        )
    return image


# --------------------------------------------------------------------------- background
class Background:
    """Background image: captured on demand (median of frames), then slowly updated by a
    running average where no hand is seen. ``image`` is the float average; ``u8`` its
    rounded 8-bit copy, kept current by ``update`` (what each frame is compared with)."""

    def __init__(self, image: np.ndarray | None = None, alpha: float = 0.02) -> None:
        self.alpha = float(alpha)
        self.image: np.ndarray | None = None
        self.u8: np.ndarray | None = None
        if image is not None:
            self._set(np.asarray(image).astype(np.float32))

    def _set(self, image: np.ndarray) -> None:
        self.image = image
        self.u8 = cv2.convertScaleAbs(image)  # rounded and clipped to 0..255

    def capture(self, frames: list[np.ndarray]) -> None:
        """Set the background to the per-pixel median of ``frames`` (an empty table)."""
        if not frames:
            raise UserError("background capture: no frames; show the empty table for a moment")
        self._set(np.median(np.stack(frames).astype(np.float32), axis=0))

    def update(self, frame: np.ndarray, foreground: np.ndarray | None = None) -> None:
        """Blend ``frame`` in with weight ``alpha``, except under ``foreground`` (mask)."""
        if self.image is None:
            self._set(frame.astype(np.float32))
            return
        if foreground is None:
            cv2.accumulateWeighted(frame, self.image, self.alpha)
        else:
            keep = cv2.compare(foreground, 0, cv2.CMP_EQ)
            cv2.accumulateWeighted(frame, self.image, self.alpha, mask=keep)
        cv2.convertScaleAbs(self.image, self.u8)

    def as_uint8(self) -> np.ndarray:
        if self.image is None:
            raise UserError("background: none captured yet; capture the empty table first")
        return self.u8.copy()


def _median(a: np.ndarray) -> float:
    """``np.median`` of a 1-d array through one single-index ``np.partition``: a fifth of
    the time on the few thousand samples the per-frame fits use (a partition about two
    indices takes numpy's slow path, six times slower on fresh data than about one: the
    lower middle of an even count is the largest element left of the upper one)."""
    n = a.size
    k = n // 2
    p = np.partition(a, k)
    if n % 2:
        return float(p[k])
    return 0.5 * (float(p[:k].max()) + float(p[k]))


def brightness_gain(frame: np.ndarray, background: np.ndarray, step: int = 8) -> float:
    """Global frame / background brightness ratio (median over a pixel grid)."""
    f = frame[::step, ::step].astype(np.float32)
    b = background[::step, ::step].astype(np.float32)
    ok = b > 4
    if not np.any(ok):
        return 1.0
    return _median(f[ok] / b[ok])


def illumination(
    frame: np.ndarray, background: np.ndarray, step: int = 12
) -> tuple[float, float, float]:
    """``(gain, offset, noise)`` with ``frame ~ gain * background + offset`` over the
    empty parts of the table: a least-squares line on a pixel grid, refitted twice on the
    pixels whose residual is not far above the median (hands, brighter than predicted,
    drop out). ``noise`` is the residuals' robust standard deviation (1.4826 MAD), the
    noise of the difference image."""
    f = frame[::step, ::step].astype(np.float32).ravel()
    b = background[::step, ::step].astype(np.float32).ravel()
    fk, bk = f, b  # the first fit uses every pixel
    gain, offset, mad = 1.0, 0.0, 0.0
    for it in range(3):
        n = len(fk)
        if n < 10:
            break
        # means as ndarray.mean takes them (float32 sum / n), with less overhead
        mb, mf = float(np.add.reduce(bk) / n), float(np.add.reduce(fk) / n)
        db = bk - mb
        var = float(np.dot(db, db)) / n
        if var < 4.0:  # too little contrast in the background for a line: an offset
            gain, offset = 1.0, _median(fk - bk)
        else:
            gain = float(np.dot(db, fk - mf)) / n / var
            offset = mf - gain * mb
        res = f - (gain * b + offset)
        med = _median(res)
        mad = _median(np.abs(res - med))
        if it < 2:
            keep = res <= med + 2.0 * mad + 1.0
            fk, bk = f[keep], b[keep]
    noise = 1.4826 * mad
    if not (0.2 < gain < 5.0):
        return brightness_gain(frame, background, step), 0.0, noise
    return gain, offset, noise


def subtract(
    frame: np.ndarray, background: np.ndarray, gain: float = 1.0, offset: float = 0.0
) -> np.ndarray:
    """``frame - (gain * background + offset)`` clipped at 0, as uint8."""
    if gain == 1.0 and offset == 0.0 and background.dtype == np.uint8:
        return cv2.subtract(frame, background)
    return cv2.subtract(frame, cv2.convertScaleAbs(background, alpha=gain, beta=offset))


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


# --------------------------------------------------------------------------- contacts
def find_contacts(
    hp: np.ndarray,
    threshold: float,
    min_area_px: int = 3,
    max_area_px: int = 2500,
    to_mm=None,
    max_size_px: int = 45,
    origin_px: tuple[int, int] = (0, 0),
) -> list[Contact]:
    """Bright blobs of the high-pass image: intensity-weighted centroid and area.

    Pixels above ``threshold`` are grouped after a 5 px dilation, so the broken rim
    that a flat palm leaves in the high-pass image becomes one large blob, rejected by
    ``max_size_px`` (bounding box) or ``max_area_px``; fingertips stay separate.
    ``hp`` may be a crop of the frame's high-pass at ``origin_px`` (x, y): positions
    are in the frame's pixels.
    """
    _, m = cv2.threshold(hp, threshold, 255, cv2.THRESH_BINARY)
    md = cv2.dilate(m, _DISK5)
    groups, _ = cv2.findContours(md, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
    out: list[Contact] = []
    for g in groups:
        x0, y0, w, h = cv2.boundingRect(g)
        if max(w, h) - 4 > max_size_px:  # the dilation adds 2 px each side
            continue
        sel = np.zeros((h, w), np.uint8)
        cv2.drawContours(sel, [g], -1, 1, thickness=cv2.FILLED, offset=(-x0, -y0))
        sub = m[y0 : y0 + h, x0 : x0 + w] & sel
        area = int(cv2.countNonZero(sub))
        if area < min_area_px or area > max_area_px:
            continue
        hps = hp[y0 : y0 + h, x0 : x0 + w]
        mo = cv2.moments(cv2.bitwise_and(hps, hps, mask=sub))  # integer sums: exact
        if mo["m00"] <= 0:
            continue
        gx, gy = x0 + origin_px[0], y0 + origin_px[1]
        pos = (gx + mo["m10"] / mo["m00"], gy + mo["m01"] / mo["m00"])
        out.append(Contact(id=len(out), pos_px=pos, area_px=float(area)))
    out.sort(key=lambda c: (c.pos_px[1], c.pos_px[0]))
    out = [Contact(i, c.pos_px, c.pos_mm, c.area_px) for i, c in enumerate(out)]
    if to_mm is not None and out:
        mm = np.asarray(to_mm(np.array([c.pos_px for c in out])))
        out = [
            Contact(c.id, c.pos_px, (float(q[0]), float(q[1])), c.area_px)
            for c, q in zip(out, mm, strict=True)
        ]
    return out


_DISK5 = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (5, 5))


# --------------------------------------------------------------------------- geometry
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


def brightness_axis(
    mask: np.ndarray,
    diff: np.ndarray,
    min_shift_px: float = 1.0,
    bright: tuple[float, float] | None = None,
) -> float | None:
    """Direction (rad) from the brightness-weighted centroid of a hand to its plain
    centroid: towards the dimmer forearm. None if the two nearly coincide."""
    m0 = cv2.moments(mask, binaryImage=True)
    if m0["m00"] <= 0:
        return None
    b = bright if bright is not None else bright_centroid(mask, diff)
    if b is None:
        return None
    dx = m0["m10"] / m0["m00"] - b[0]
    dy = m0["m01"] / m0["m00"] - b[1]
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
    small = cv2.resize(mask, (max(w // k, 1), max(h // k, 1)), interpolation=cv2.INTER_AREA)
    _, small = cv2.threshold(small, 127, 255, cv2.THRESH_BINARY)
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
) -> np.ndarray | None:
    """The hand rotated about the palm centre so the wrist points down, forearm cut off
    ``wrist_cut`` palm radii below the centre: its largest outer contour (N, 2) float in
    a frame whose origin is the palm centre. None if nothing is left."""
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
    # only the rows above the cut are made (each output pixel depends on its own
    # position alone, so they are the top rows of the whole rotated square)
    rot = cv2.warpAffine(mask, m, (size, min(cut, size)), flags=cv2.INTER_NEAREST)
    contours, _ = cv2.findContours(rot, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
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


def brightness_grid(
    roi_mask: np.ndarray,
    roi_diff: np.ndarray,
    center: tuple[float, float],
    palm_radius: float,
    angle_deg: float,
) -> np.ndarray:
    """Share of the hand's brightness in each cell of a polar grid in the canonical frame
    (``GRID_SECTORS`` sectors x rings ``GRID_RINGS`` palm radii): where the hand touches
    or nearly touches the glass, independent of position, rotation, size and gain."""
    ys, xs = np.nonzero(roi_mask[::3, ::3])
    n_cells = GRID_SECTORS * (len(GRID_RINGS) - 1)
    if len(xs) == 0 or palm_radius <= 0:
        return np.zeros(n_cells)
    w = roi_diff[::3, ::3][ys, xs].astype(np.float64)
    u, v = _canonical_xy(xs * 3, ys * 3, center, angle_deg, palm_radius)
    r = np.hypot(u, v)
    sector = ((np.arctan2(v, u) + math.pi) / (2 * math.pi) * GRID_SECTORS).astype(int)
    sector = np.minimum(np.maximum(sector, 0, out=sector), GRID_SECTORS - 1, out=sector)
    ring = np.searchsorted(GRID_RINGS, r, side="right") - 1
    ok = (ring >= 0) & (ring < len(GRID_RINGS) - 1)
    cells = np.bincount(ring[ok] * GRID_SECTORS + sector[ok], weights=w[ok], minlength=n_cells)
    total = cells.sum()
    return cells / total if total > 0 else cells


# --------------------------------------------------------------------------- one frame
def analyse_hand(
    contour: np.ndarray,
    full_mask: np.ndarray,
    params: VisionParams,
    diff: np.ndarray | None = None,
    contacts: list[Contact] | None = None,
    to_mm=None,
) -> tuple[Hand, dict] | None:
    """Everything about one hand component (contour from ``cv2.findContours``): the
    ``Hand`` and its extras (see ``FrameResult.extras``)."""
    x0, y0, w, h = cv2.boundingRect(contour)
    pad = 2
    H, W = full_mask.shape
    xa, ya = max(x0 - pad, 0), max(y0 - pad, 0)
    xb, yb = min(x0 + w + pad, W), min(y0 + h + pad, H)
    roi = np.zeros((yb - ya, xb - xa), np.uint8)
    cv2.drawContours(roi, [contour], -1, 255, thickness=cv2.FILLED, offset=(-xa, -ya))
    (pcx, pcy), pr = palm(roi)
    if pr < 1.0:
        return None
    center = (pcx + xa, pcy + ya)
    pts = contour.reshape(-1, 2).astype(np.float64)
    hint = None
    bright = None
    if diff is not None:
        bright = bright_centroid(roi, diff[ya:yb, xa:xb])
        hint = brightness_axis(roi, diff[ya:yb, xa:xb], 0.1 * pr, bright)
    bright_px = center if bright is None else (bright[0] + xa, bright[1] + ya)
    arc = wrist_arc(roi, (pcx, pcy), pr, params, pts - (xa, ya), (xa, ya), (H, W), hint)
    angle = canonical_angle_deg(arc.mid_rad)
    roi_center = (pcx, pcy)
    sil = canonical_silhouette(roi, roi_center, pr, angle, params)
    if sil is None or len(sil) < 3:
        return None
    (ecx, ecy), er = cv2.minEnclosingCircle(sil.astype(np.float32))
    # enclosing circle centre back in image coordinates (inverse rotation about the palm)
    t = math.radians(angle)
    ex = center[0] + ecx * math.cos(t) - ecy * math.sin(t)
    ey = center[1] + ecx * math.sin(t) + ecy * math.cos(t)
    desc = fourier_descriptors(
        sil, params.n_harmonics, rotation_invariant=params.rotation_invariant
    )
    fingers = count_fingers(sil, pr, params)
    mine: tuple[Contact, ...] = ()
    if contacts:
        mine = tuple(
            c
            for c in contacts
            if 0 <= int(c.pos_px[1]) < H
            and 0 <= int(c.pos_px[0]) < W
            and cv2.pointPolygonTest(contour, (float(c.pos_px[0]), float(c.pos_px[1])), True) >= -3
        )
    center_mm = None
    if to_mm is not None:
        cm = np.asarray(to_mm(np.array([[ex, ey]])))[0]
        center_mm = (float(cm[0]), float(cm[1]))
    grid = (
        brightness_grid(roi, diff[ya:yb, xa:xb], (pcx, pcy), pr, angle)
        if diff is not None
        else np.zeros(GRID_SECTORS * (len(GRID_RINGS) - 1))
    )
    canon = (
        to_canonical(np.array([c.pos_px for c in mine]), center, angle, pr)
        if mine
        else np.zeros((0, 2))
    )
    extras = {
        "palm_radius_px": pr,
        "palm_px": center,
        "bright_px": bright_px,
        "grid": grid,
        "contacts_canon": canon,
    }
    return Hand(
        contour_px=pts,
        center_px=(float(ex), float(ey)),
        radius_px=float(er),
        angle_deg=float(angle),
        descriptors=desc,
        finger_count=fingers,
        contacts=mine,
        center_mm=center_mm,
    ), extras


def process_frame(
    image: np.ndarray,
    background: np.ndarray,
    params: VisionParams | None = None,
    *,
    to_mm=None,
    keep_masks: bool = False,
) -> FrameResult:
    """Run the whole pipeline on one frame against a background image (uint8 or float)."""
    p = params or VisionParams()
    img = check_frame(image, p.shape)
    bg = np.asarray(background)
    if bg.shape != img.shape:
        raise UserError(
            f"background: size {bg.shape[1]} x {bg.shape[0]} px does not match the frame "
            f"({img.shape[1]} x {img.shape[0]}); capture the background again"
        )
    gain, offset, noise = illumination(img, bg)
    changed = abs(gain - 1.0) > p.illumination_tolerance or abs(offset) > p.offset_tolerance
    if abs(gain - 1.0) < 0.02 and abs(offset) < 1.5:
        gain, offset = 1.0, 0.0
    if bg.dtype != np.uint8 and gain == 1.0 and offset == 0.0:
        bg = np.clip(bg + 0.5, 0, 255).astype(np.uint8)
    diff = subtract(img, bg, gain, offset)
    # thresholds rise with the noise (each at least its profile value)
    body_thr = max(p.body_threshold, 4.0 * noise / max(p.smooth_px, 1) + 2.0)
    contact_thr = max(p.contact_threshold, 4.0 * noise / 3.0 + 2.0)
    # hands and contacts: only around the pixels above the thresholds (the rest of the
    # frame cannot reach them through the smoothing); the same results as the whole frame
    body, body_win = body_window(diff, body_thr, p.smooth_px)
    if contact_thr < body_thr:
        win = contact_window(diff, contact_thr)
    else:  # contact pixels are above the body threshold too: in the body's window
        win = None if body_win is None else contact_window(diff, contact_thr, body_win)
    contacts = []
    if win is not None:
        contacts = find_contacts(
            highpass_window(diff, p.highpass_sigma_px, win),
            contact_thr,
            p.min_contact_area_px,
            p.max_contact_area_px,
            to_mm,
            p.max_contact_size_px,
            origin_px=win[:2],
        )
    contours = ()
    if body_win is not None:
        x0, y0, x1, y1 = body_win
        contours, _ = cv2.findContours(
            body[y0:y1, x0:x1], cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE, offset=(x0, y0)
        )
    found = []
    max_area = p.max_hand_fraction * img.shape[0] * img.shape[1]
    for c in contours:
        if not p.min_hand_area_px <= cv2.contourArea(c) <= max_area:
            continue
        got = analyse_hand(c, body, p, diff, contacts, to_mm)
        if got is not None:
            found.append(got)
    found.sort(key=lambda he: -cv2.contourArea(he[0].contour_px.astype(np.float32)))
    masks: Mapping[str, np.ndarray] = {}
    if keep_masks:  # the whole high-pass image only if someone looks at it
        sigma = p.highpass_sigma_px
        masks = Masks(
            {"diff": diff, "body": body},
            {"highpass": functools.partial(frame_highpass, diff, sigma)},
        )
    return FrameResult(
        hands=tuple(h for h, _ in found),
        contacts=tuple(contacts),
        gain=float(gain),
        offset=float(offset),
        noise=float(noise),
        illumination_changed=bool(changed),
        masks=masks,
        extras=tuple(e for _, e in found),
    )
