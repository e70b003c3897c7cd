"""Segmentation of the difference image: the high-pass image (sharp bright parts touching
the glass), the body mask (hands and forearms, including the dim parts above the glass,
each part at a threshold that follows its own light: ``relative_body``), and the windows
of the frame where either can be non-zero, so the pipeline works on crops only (with
results equal to the whole frame's)."""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field

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
    ``cv2.threshold`` makes) of an 8-bit ``image``, looked for in the box ``within`` only
    if given; None if there are none."""
    ox, oy = 0, 0
    if within is not None:
        ox, oy, x1, y1 = within
        image = image[oy:y1, ox:x1]
    # the mask's box: two OpenCV passes, half the time of numpy's column and row maxima
    _, above = cv2.threshold(image, threshold, 255, cv2.THRESH_BINARY)
    x, y, w, h = cv2.boundingRect(above)
    if w == 0:
        return None
    return x + ox, y + oy, x + w + ox, y + h + oy


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


#: parts are found on block means of this size; a part is a hand's when its brightest
#: block rises this many times above the noise floor
PART_BLOCK_PX = 4
SEED_FACTOR = 2.5
#: the parts' box is found from each part's pixels for up to this many parts (a hand or
#: two: cheaper than the labelling's statistics), from the statistics for more
MAX_BOXES_APART = 4


@dataclass(frozen=True)
class Parts:
    """The body's connected parts at the lowest threshold, each with the light it shows:
    ``blocks`` (int32, one label per ``PART_BLOCK_PX`` block of the frame; 0 = no hand's
    part), ``scale[i]`` the brightness of part i relative to the reference level,
    ``peak[i]`` its brightest block mean (grey levels above the background; 0 for the
    labels that are no hand's part), and
    ``win`` (x0, y0, x1, y1) the frame's box that holds every hand's part."""

    win: tuple[int, int, int, int]
    blocks: np.ndarray
    scale: np.ndarray
    peak: np.ndarray
    #: the labels at full resolution over ``win`` (uint8), made on first use and shared
    #: by every ``image`` of this frame (the body's thresholds, the contacts', the
    #: foreground): one upsampling per frame, then a table look-up per image
    _cache: dict = field(default_factory=dict, compare=False, repr=False)

    def label_at(self, x: int, y: int) -> int:
        """The part at pixel (x, y) of the frame (0: none)."""
        b = PART_BLOCK_PX
        by, bx = y // b, x // b
        if 0 <= by < self.blocks.shape[0] and 0 <= bx < self.blocks.shape[1]:
            return int(self.blocks[by, bx])
        return 0

    def _upsampled(self, values: np.ndarray | None, box: tuple[int, int, int, int]) -> np.ndarray:
        """``image`` by nearest-neighbour upsampling of ``values[blocks]`` (any dtype; None:
        the labels themselves, as uint8, each below 256)."""
        b = PART_BLOCK_PX
        x0, y0, x1, y1 = box
        bx0, by0 = x0 // b, y0 // b
        bx1, by1 = -(-x1 // b), -(-y1 // b)
        if values is None:
            blk = np.zeros((by1 - by0, bx1 - bx0), np.uint8)
        else:
            blk = np.full((by1 - by0, bx1 - bx0), values[0], values.dtype)
        hb, wb = self.blocks.shape
        sub = self.blocks[by0 : min(by1, hb), bx0 : min(bx1, wb)]
        blk[: sub.shape[0], : sub.shape[1]] = sub if values is None else values[sub]
        up = cv2.resize(blk, None, fx=b, fy=b, interpolation=cv2.INTER_NEAREST)
        return up[y0 - by0 * b : y1 - by0 * b, x0 - bx0 * b : x1 - bx0 * b]

    def labels(self) -> np.ndarray | None:
        """The part at every pixel of ``win`` (uint8, 0 where none; made once per frame
        and shared: do not write to it), or None if a label exceeds 255."""
        if "labels" not in self._cache:
            # every label is below the labelling's count (no look-up of the largest)
            ok = len(self.peak) <= 256 or int(self.blocks.max(initial=0)) < 256
            # contiguous: each look-up over it is a quarter faster than over a strided view
            self._cache["labels"] = (
                np.ascontiguousarray(self._upsampled(None, self.win)) if ok else None
            )
        return self._cache["labels"]

    def image(self, values: np.ndarray, box: tuple[int, int, int, int]) -> np.ndarray:
        """``values[part]`` at every pixel of ``box`` (x0, y0, x1, y1) of the frame, in
        ``values``' dtype (``values[0]`` where no part is)."""
        labels = self.labels() if values.dtype == np.uint8 else None
        if labels is None:
            return self._upsampled(values, box)
        # every block outside ``win`` is no part's: values[0] there
        lut = np.full(256, values[0], np.uint8)
        lut[: min(len(values), 256)] = values[:256]
        x0, y0, x1, y1 = box
        wx0, wy0, wx1, wy1 = self.win
        if (x0, y0, x1, y1) == (wx0, wy0, wx1, wy1):
            return cv2.LUT(labels, lut)
        out = np.full((y1 - y0, x1 - x0), values[0], np.uint8)
        ix0, iy0, ix1, iy1 = max(x0, wx0), max(y0, wy0), min(x1, wx1), min(y1, wy1)
        if ix0 < ix1 and iy0 < iy1:
            out[iy0 - y0 : iy1 - y0, ix0 - x0 : ix1 - x0] = cv2.LUT(
                labels[iy0 - wy0 : iy1 - wy0, ix0 - wx0 : ix1 - wx0], lut
            )
        return out


def relative_body(
    diff: np.ndarray,
    threshold: float,
    reference: float,
    noise: float,
    smooth_px: int = 5,
    scale_range: tuple[float, float] = (0.3, 2.0),
) -> tuple[np.ndarray, Parts | None]:
    """``body_parts``' mask as the whole frame's (uint8 0/255, 0 outside the parts'
    window) and the parts."""
    inside, parts = body_parts(diff, threshold, reference, noise, smooth_px, scale_range)
    return full_body(inside, parts, diff.shape), parts


def full_body(inside: np.ndarray | None, parts: Parts | None, shape: tuple[int, int]) -> np.ndarray:
    """The frame-sized body mask from ``body_parts``' mask of the parts' window."""
    body = np.zeros(shape, np.uint8)
    if parts is not None:
        x0, y0, x1, y1 = parts.win
        body[y0:y1, x0:x1] = inside
    return body


def body_parts(
    diff: np.ndarray,
    threshold: float,
    reference: float,
    noise: float,
    smooth_px: int = 5,
    scale_range: tuple[float, float] = (0.3, 2.0),
    *,
    hand_likely: bool = False,
    seed_factor: float = SEED_FACTOR,
) -> tuple[np.ndarray | None, Parts | None]:
    """Hands and forearms with a threshold that follows each part's own light.

    The parts are found on the difference image's 4 x 4 block means (cheap, and their
    noise is a quarter of a pixel's): connected regions above the lowest threshold any
    part can have (``threshold`` x the smallest scale, and at least 4 sigma of the block
    noise, ``noise`` being a pixel's). A part whose brightest block rises well above the
    noise (``seed_factor`` x that floor) is a hand's; its scale is that brightness over
    ``reference``, kept within ``scale_range``. Each part is then cut at full resolution
    (``smooth_px`` box mean) at ``threshold`` x its scale. Touching skin is a part's
    brightest; it rises and falls with the IR light reaching that hand (LED power, hot
    spots, vignetting), so the parts of a hand above the glass keep their extent under
    another light.

    The mask (uint8 0/255) of the parts' window ``parts.win`` (the body is 0 outside it:
    no frame-sized mask is made) and the parts; (None, None) without a hand's part.
    ``hand_likely`` (the frame before had a hand's part) skips the empty table's shortcut,
    a pass over the frame for its brightest pixel: the same result either way.
    ``seed_factor``: how far above the noise floor a part's brightest block must rise."""
    H, W = diff.shape
    b = PART_BLOCK_PX
    hb, wb = H // b, W // b
    floor = 4.0 * noise / b + 2.0
    low = max(threshold * scale_range[0], floor)
    seed_level = max(low, seed_factor * floor)
    # no block's mean exceeds its brightest pixel: a frame with no pixel at a seed's level
    # (an empty table: its noise stays below) has no hand's part, and its block means
    # need not be made (made, they would hold no seed: the same answer below)
    if not hand_likely and cv2.minMaxLoc(diff)[1] < seed_level:
        return None, None
    small = block_means(diff)
    _, lowm = cv2.threshold(small, low, 255, cv2.THRESH_BINARY)
    n, lab = cv2.connectedComponents(lowm, connectivity=8, ltype=cv2.CV_16U)
    # a hand's part rises above the lowest threshold and well above the noise (specks of
    # noise and background drift do not): the parts holding such a block, whose
    # brightest block is one of those (small >= seed_level is small >= its ceiling)
    level = math.ceil(seed_level)
    if level > 255:
        return None, None
    seeds = small >= level
    seed_lab = lab[seeds]
    real = np.zeros(n, bool)
    real[seed_lab] = True
    real[0] = False
    seeded = np.flatnonzero(real)
    if len(seeded) == 0:
        return None, None
    # each part's brightest block (one of its seeds) and the grown parts' box: the parts'
    # boxes, one block wider on each side
    peak = np.zeros(n)
    c0, r0, c1, r1 = _parts_box(lab, seeded, lowm, small, peak)
    if len(seeded) > MAX_BOXES_APART:
        seed_val = small[seeds]
        for i in seeded:
            peak[i] = float(seed_val[seed_lab == i].max())
    c0, r0 = max(c0 - 1, 0), max(r0 - 1, 0)
    c1, r1 = min(c1 + 1, wb), min(r1 + 1, hb)
    # each block keeps its part's label, grown by one block so a part's edge pixels
    # (brighter than their block's mean) keep it too: made in that box only (outside
    # it every block is two or more from a hand's part: 0)
    keep = np.where(real, np.arange(n), 0).astype(np.uint16)
    blocks = np.zeros((hb, wb), np.int32)
    blocks[r0:r1, c0:c1] = cv2.dilate(keep[lab[r0:r1, c0:c1]], _BLOCK3)
    reach = smooth_px // 2 if smooth_px > 1 else 0
    box = (c0 * b, r0 * b, c1 * b, r1 * b)
    x0, y0, x1, y1 = win = _grow(box, reach, diff.shape)
    cx0, cy0, cx1, cy1 = _grow(win, reach, diff.shape)
    src = diff[cy0:cy1, cx0:cx1]
    sm = cv2.blur(src, (smooth_px, smooth_px)) if smooth_px > 1 else src
    sm = sm[y0 - cy0 : y1 - cy0, x0 - cx0 : x1 - cx0]
    scale = np.ones(n)
    # np.clip's value, for a third of its call's cost on a few parts
    scale[real] = np.minimum(np.maximum(peak[real] / reference, scale_range[0]), scale_range[1])
    # sm > t for an integer sm is sm > floor(t): one uint8 threshold per part, 255 = never
    thr = np.where(real, np.floor(np.maximum(threshold * scale, low)), 255)
    thr[0] = 255
    parts = Parts(win, blocks, scale, peak)
    limit = parts.image(np.minimum(thr, 255).astype(np.uint8), win)
    return cv2.compare(sm, limit, cv2.CMP_GT), parts


_BLOCK3 = np.ones((3, 3), np.uint8)
_HALVES = np.uint64(0x0000FFFF0000FFFF)


def block_means(diff: np.ndarray) -> np.ndarray:
    """The means of the frame's whole ``PART_BLOCK_PX`` blocks, rounded half to even: what
    ``cv2.resize`` with ``INTER_AREA`` gives, for two thirds of its cost with 4 px blocks
    of a little-endian frame whose width is a multiple of 4 (each block's 4 column sums
    read as one 64-bit word and summed two at a time in its halves)."""
    b = PART_BLOCK_PX
    H, W = diff.shape
    hb, wb = H // b, W // b
    if b != 4 or W % 4 or sys.byteorder != "little" or not diff.flags.c_contiguous:
        return cv2.resize(diff[: hb * b, : wb * b], (wb, hb), interpolation=cv2.INTER_AREA)
    rows = diff[: hb * b]
    cols = np.add(rows[0::b], rows[1::b], dtype=np.uint16)
    cols += np.add(rows[2::b], rows[3::b], dtype=np.uint16)  # 4 rows' sums, at most 1020
    words = cols.view(np.uint64)  # (hb, wb): a block's 4 column sums in each word
    pairs = words & _HALVES  # columns 0 and 2 of each block, each in a 32-bit half
    words >>= np.uint64(16)
    words &= _HALVES  # columns 1 and 3
    pairs += words
    halves = pairs.view(np.uint32)  # (hb, 2 wb): each block's 0 + 1 and 2 + 3
    total = halves[:, 0::2] + halves[:, 1::2]  # the block's sum s of 16 pixels
    # s / 16 rounded half to even: (s + 8) // 16, less 1 where s is 16 q + 8 with q even
    tie = (total & np.uint32(31)) == 8
    total += np.uint32(8)
    total -= tie
    total >>= 4
    return total.astype(np.uint8)


def _parts_box(
    lab: np.ndarray, seeded: np.ndarray, lowm: np.ndarray, small: np.ndarray, peak: np.ndarray
) -> tuple[int, int, int, int]:
    """(c0, r0, c1, r1): the box holding every pixel of the labels ``seeded`` in the
    label image ``lab`` (of ``lowm``): from each part's pixels (a few parts; each part's
    brightest value of ``small`` written to ``peak`` on the way), else from the
    labelling's statistics (the same labels; ``peak`` left as it is)."""
    if len(seeded) <= MAX_BOXES_APART:
        boxes = []
        for i in seeded:
            mine = cv2.compare(lab, int(i), cv2.CMP_EQ)
            boxes.append(cv2.boundingRect(mine))
            peak[i] = cv2.minMaxLoc(small, mine)[1]
        return (
            min(x for x, _, _, _ in boxes),
            min(y for _, y, _, _ in boxes),
            max(x + w for x, _, w, _ in boxes),
            max(y + h for _, y, _, h in boxes),
        )
    _, _, stats, _ = cv2.connectedComponentsWithStats(lowm, connectivity=8, ltype=cv2.CV_16U)
    st = stats[seeded]
    return (
        int(st[:, cv2.CC_STAT_LEFT].min()),
        int(st[:, cv2.CC_STAT_TOP].min()),
        int((st[:, cv2.CC_STAT_LEFT] + st[:, cv2.CC_STAT_WIDTH]).max()),
        int((st[:, cv2.CC_STAT_TOP] + st[:, cv2.CC_STAT_HEIGHT]).max()),
    )
