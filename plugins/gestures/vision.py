"""Rear-DI vision pipeline, one frame: its settings (``VisionParams``), its result
(``FrameResult``), the input check and ``process_frame``, which runs the steps held by the
sibling modules: ``background`` (background model, illumination, subtraction),
``segmentation`` (high-pass, the body's parts and the windows they are made in), ``contacts``
(contact blobs) and ``hand_shape`` (palm, wrist, canonical pose, fingers).
Pure functions of arrays (numpy + OpenCV 5); the one stateful part, the background
model, is in ``background``.

Steps for one frame (paper section 3, Fig. 4):

1. ``check_frame``: 2-D uint8 of the expected size, else a ``UserError``.
2. ``subtract``: frame minus the background, after matching the global brightness
   (a sudden illumination change is a gain and an offset on the whole frame: a robust
   line fit of frame against background over a pixel grid estimates them; the hands
   cover a minority of the pixels and are left out as the brighter residuals).
3. ``relative_body``: the smoothed difference split into parts (on 4 px block means),
   each cut at ``body_threshold`` scaled by the light that part shows (its brightest
   block over ``contact_level``): hands and forearms, including the dim, blurred parts
   above the glass, with the same extent under another light.
4. ``highpass`` (difference minus its blur) above ``contact_threshold``, scaled the same
   way per part: the sharp bright parts touching the glass -> contact blobs. Both
   thresholds stay above the noise measured in step 2.
5. per part (a hand whose pieces the threshold split stays one): its largest piece's
   palm centre (maximum of the distance transform), the forearm
   direction (the thick part reaching farthest, or leaving the image; its sign checked
   against the brightness axis, as the forearm is higher above the glass and dimmer),
   the wrist arc where it crosses a circle about the palm, the angle that turns the
   wrist to the reference edge (image bottom), the hand rotated about the centre, the
   wrist and forearm cut off, the smallest enclosing circle, Fourier descriptors of the
   canonical silhouette and the number of extended fingers.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np

from console.plugin_api import Contact, Hand, HandShape, UserError

from .background import illumination, subtract
from .contacts import find_contacts
from .descriptors import fourier_descriptors
from .hand_shape import (
    bright_centroid,
    brightness_axis,
    canonical_angle_deg,
    canonical_silhouette,
    count_fingers,
    palm,
    to_canonical,
    wrist_arc,
)
from .segmentation import (
    Parts,
    body_parts,
    contact_window,
    frame_highpass,
    full_body,
    highpass_window,
)
from .touch import SAME_HAND_MM, FrameTouch, default_px_per_mm

#: the range a hand's light may scale the thresholds by (a hand dimmer than 0.3 of the
#: reference is mostly noise; brighter than 2x, the sensor clips)
SCALE_RANGE = (0.3, 2.0)
#: seeds nearer the noise floor (``segmentation.SEED_FACTOR``: 2.5) for a frame whose
#: parts hold no hand: a hovering hand's palm under dim light (``process_frame``)
DIM_SEED_FACTOR = 1.5


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
    #: touching skin's brightness (grey levels above the background, its brightest 5 px
    #: mean) the two thresholds are given for (about 183 on the twin at its nominal
    #: light): > 0 (default), each hand's thresholds scale with the brightness that hand
    #: shows, so its hovering parts and contacts keep their extent under another light
    #: (``segmentation.relative_body``); 0: fixed thresholds in grey levels
    contact_level: float = 180.0
    #: the camera's scale on the glass (px per mm; 0: the frame seeing the whole glass,
    #: ``touch.default_px_per_mm``): gesture features are lengths in mm
    px_per_mm: float = 0.0
    illumination_tolerance: float = 0.15  # |gain - 1| above this flags an illumination change
    offset_tolerance: float = 8.0  # |offset| grey levels above this flags one too

    @property
    def shape(self) -> tuple[int, int]:
        return (self.height_px, self.width_px)

    @property
    def scale_px_per_mm(self) -> float:
        """``px_per_mm``, or the frame's default when it is 0."""
        return self.px_per_mm or default_px_per_mm(self.width_px, self.height_px)


def vision_params(profile: Any) -> VisionParams:
    """``VisionParams`` from the profile's ``[vision]`` and ``[camera]`` sections (the
    defaults without a profile)."""
    v = profile.section("vision") if profile is not None else {}
    cam = profile.section("camera") if profile is not None else {}
    keys = set(VisionParams.__dataclass_fields__)
    kw = {k: v[k] for k in v if k in keys}
    if "width_px" in cam:
        kw["width_px"] = int(cam["width_px"])
    if "height_px" in cam:
        kw["height_px"] = int(cam["height_px"])
    return VisionParams(**kw)


@dataclass(frozen=True)
class FrameResult:
    """What the pipeline found in one frame."""

    hands: tuple[Hand, ...]
    contacts: tuple[Contact, ...]  # all contact blobs, hands or not
    gain: float = 1.0  # frame ~ gain * background + offset (the fit, however small)
    offset: float = 0.0
    noise: float = 0.0  # robust std of the difference image (grey levels)
    illumination_changed: bool = False
    #: pixels of the hands' outlines at the sensor's maximum (255): touching skin clips,
    #: so the hands' light and thresholds are underestimated; lower exposure or gain
    clipped_px: int = 0
    #: pixels of the hands' touching skin (at least half their part's level, or clipped):
    #: ``clipped_px`` over this is the clipped share (``clipped_share``); 0 unless some clip
    touching_px: int = 0
    #: "diff", "body", "highpass" and "foreground" (the last three computed on first
    #: access) with ``keep_masks``
    masks: Mapping[str, np.ndarray] = field(default_factory=dict, compare=False, repr=False)
    #: per hand (same order as ``hands``): palm_radius_px, palm_px, bright_px (the
    #: brightness-weighted centroid), contacts_canon ((k, 2) in palm radii), level (the
    #: hand's brightest block, grey levels above the background), light (level over
    #: ``contact_level``, the scale of its thresholds; 1.0 with fixed thresholds),
    #: and px_per_mm
    extras: tuple[dict, ...] = field(default=(), compare=False, repr=False)
    #: the hands' touching skin (``touch.FrameTouch``: found when first asked, per hand
    #: in ``hands``' order); None without a hand
    touch: FrameTouch | None = field(default=None, compare=False, repr=False)
    #: the body's parts (``segmentation.Parts``; None without a hand's part): where the
    #: foreground lies (``foreground_window``)
    parts: Parts | None = field(default=None, compare=False, repr=False)

    def view(self, name: str) -> np.ndarray | None:
        """The intermediate image ``name`` (``diff``, ``body``, ``highpass``), or ``None``
        when this result kept none (``console.core.contracts.VisionResult``)."""
        return self.masks.get(name)

    def readings(self) -> dict[str, float]:
        """What an operator tunes against (``console.core.contracts.VisionResult``): the
        main hand's touch level and light scale, its touching skin's area (``touching
        mm2``: a flat hand touches with its palm and fingers, no fingertip apart, so it
        has no contact blob), clipped pixels, the noise and the illumination gain
        against the background."""
        out: dict[str, float] = {}
        if self.extras:
            out["touch level"] = float(self.extras[0]["level"])
            out["light x"] = float(self.extras[0]["light"])
        if self.touch is not None and self.hands:
            out["touching mm2"] = float(self.touch.of(0)["area_mm2"])
        out["clipped px"] = float(self.clipped_px)
        out["noise"] = float(self.noise)
        out["gain"] = float(self.gain)
        return out


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

    def with_image(self, name: str, image: np.ndarray) -> Masks:
        """These images plus ``name``."""
        return Masks({**self._images, name: image}, self._makers)

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


# --------------------------------------------------------------------------- one frame
def analyse_hand(
    contour: np.ndarray,
    shape: tuple[int, int],
    params: VisionParams,
    diff: np.ndarray | None = None,
    contacts: list[Contact] | None = None,
    to_mm=None,
) -> tuple[Hand, dict] | None:
    """Everything about one hand (its largest piece's contour from ``cv2.findContours``
    in a frame of ``shape``; ``contacts``: the hand's own): the ``Hand`` and its extras
    (see ``FrameResult.extras``)."""
    x0, y0, w, h = cv2.boundingRect(contour)
    pad = 2
    H, W = shape
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
    local = pts - (xa, ya)  # the outline in the crop's pixels
    arc = wrist_arc(roi, (pcx, pcy), pr, params, local, (xa, ya), (H, W), hint)
    angle = canonical_angle_deg(arc.mid_rad)
    roi_center = (pcx, pcy)
    sil = canonical_silhouette(roi, roi_center, pr, angle, params, local)
    if sil is None or len(sil) < 3:
        return None
    (ecx, ecy), er = cv2.minEnclosingCircle(sil.astype(np.float32))
    # enclosing circle centre back in image coordinates (inverse rotation about the palm)
    t = math.radians(angle)
    ex = center[0] + ecx * math.cos(t) - ecy * math.sin(t)
    ey = center[1] + ecx * math.sin(t) + ecy * math.cos(t)
    mine = tuple(contacts or ())
    center_mm = None
    if to_mm is not None:
        cm = np.asarray(to_mm(np.array([[ex, ey]])))[0]
        center_mm = (float(cm[0]), float(cm[1]))
    canon = (
        to_canonical(np.array([c.pos_px for c in mine]), center, angle, pr)
        if mine
        else np.zeros((0, 2))
    )
    extras = {
        "palm_radius_px": pr,
        "palm_px": center,
        "bright_px": bright_px,
        "contacts_canon": canon,
    }
    return Hand(
        contour_px=pts,
        center_px=(float(ex), float(ey)),
        radius_px=float(er),
        angle_deg=float(angle),
        shape=HandShape(functools.partial(hand_shape, sil, pr, params)),
        contacts=mine,
        center_mm=center_mm,
    ), extras


def hand_shape(
    silhouette: np.ndarray, palm_radius: float, params: VisionParams
) -> tuple[np.ndarray, int]:
    """A hand's ``HandShape`` values from its canonical silhouette: the Fourier
    descriptors and the fingers counted."""
    desc = fourier_descriptors(
        silhouette, params.n_harmonics, rotation_invariant=params.rotation_invariant
    )
    return desc, count_fingers(silhouette, palm_radius, params)


def clipped_share(frame: np.ndarray, touching: np.ndarray) -> tuple[int, int]:
    """``(clipped, touching)`` pixel counts: of the touching-skin mask ``touching``
    (uint8 0/255, or bool), those at the sensor's maximum (255) in ``frame``."""
    t = np.asarray(touching, bool)
    return int(np.count_nonzero(frame[t] >= 255)), int(np.count_nonzero(t))


def touching_mask(img: np.ndarray, diff: np.ndarray, body: np.ndarray, parts: Parts) -> np.ndarray:
    """The hands' touching skin inside ``parts.win``: body pixels (``body``: the body's
    mask there) at least half their part's level above the background, or at the
    sensor's maximum."""
    x0, y0, x1, y1 = win = parts.win
    half = np.floor(np.minimum(0.5 * parts.peak, 255)).astype(np.uint8)
    half[0] = 255
    bright = cv2.compare(diff[y0:y1, x0:x1], parts.image(half, win), cv2.CMP_GE)
    hot = cv2.compare(img[y0:y1, x0:x1], 254, cv2.CMP_GT)
    return cv2.bitwise_and(cv2.bitwise_or(bright, hot), body)


def part_contacts(
    diff: np.ndarray,
    parts: Parts,
    p: VisionParams,
    floor: float,
    outside_scale: float,
    to_mm=None,
) -> list[Contact]:
    """The contacts in the hands' parts, each part at its own contact threshold
    (``contact_threshold`` x its light, at least ``floor``; off the parts
    ``outside_scale`` x it), looked for only around the pixels above the lowest of them."""
    # an integer high-pass exceeds t where it exceeds floor(t): one uint8 per part
    per_part = np.maximum(p.contact_threshold * parts.scale, floor)
    per_part[0] = p.contact_threshold * outside_scale
    per_part = np.floor(np.minimum(per_part, 255)).astype(np.uint8)
    win = contact_window(diff, float(per_part[parts.peak > 0].min()), parts.win)
    if win is None:
        return []
    return find_contacts(
        highpass_window(diff, p.highpass_sigma_px, win),
        parts.image(per_part, win),
        p.min_contact_area_px,
        p.max_contact_area_px,
        to_mm,
        p.max_contact_size_px,
        origin_px=win[:2],
    )


def foreground(parts: Parts | None, shape: tuple[int, int]) -> np.ndarray:
    """Everything of the hands down to the lowest threshold (uint8 0/255, the parts'
    blocks grown by one): what the background must never learn."""
    if parts is None:
        return np.zeros(shape, np.uint8)
    return parts.image(_foreground_values(parts), (0, 0, shape[1], shape[0]))


def foreground_window(parts: Parts | None) -> tuple[tuple[int, int, int, int], np.ndarray] | None:
    """``foreground`` as the box that holds all of it (``parts.win``: x0, y0, x1, y1) and
    its mask there (non-zero: foreground; the parts' labels, shared with the frame's other
    images, when each fits a byte); None without a hand's part (no foreground). A frame's
    background update works on that box only, not on a frame-sized mask."""
    if parts is None:
        return None
    labels = parts.labels()  # no part's label is 0 and every hand's part's is not
    if labels is None:
        labels = parts.image(_foreground_values(parts), parts.win)
    return parts.win, labels


def _foreground_values(parts: Parts) -> np.ndarray:
    values = np.full(len(parts.scale), 255, np.uint8)
    values[0] = 0
    return values


def hands_of(
    body: np.ndarray,
    parts: Parts | None,
    contacts: list[Contact],
    min_area_px: float,
    max_area_px: float,
    same_px: float = 0.0,
) -> list[tuple[np.ndarray, list[Contact], int]]:
    """The hands in the body's mask of the parts' window (``body``: ``parts.win``'s): per
    part (``relative_body``: everything of a hand
    above the lowest threshold), its largest piece's contour when its area is within
    the bounds (all its pieces together), the contacts that lie in that part, and the
    part's label. A hand whose fingertips touch while the fingers above them rise out of
    the mask falls into pieces; the pieces and their contacts stay one hand, and parts
    too small to be a hand join the nearest hand within ``same_px`` (or, with none,
    each other: fingertips under a palm too dim to see)."""
    if parts is None:
        return []
    x0, y0, x1, y1 = parts.win
    contours, _ = cv2.findContours(body, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE, offset=(x0, y0))
    largest: dict[int, tuple[float, np.ndarray]] = {}
    total: dict[int, float] = {}  # all of a part's pieces: fingertips under a dim palm too
    for c in contours:
        part = parts.label_at(*(int(v) for v in c[0, 0]))
        area = cv2.contourArea(c)
        total[part] = total.get(part, 0.0) + area
        if part and area > largest.get(part, (-1.0, None))[0]:
            largest[part] = (area, c)
    owner: dict[int, list[Contact]] = {}
    for c in contacts:
        part = parts.label_at(int(round(c.pos_px[0])), int(round(c.pos_px[1])))
        owner.setdefault(part, []).append(c)
    groups = {p: [p] for p in largest}
    hosts = [p for p in largest if total[p] >= min_area_px]
    if same_px > 0 and len(hosts) < len(largest):
        at = {p: np.mean(largest[p][1].reshape(-1, 2), axis=0) for p in largest}
        for p in sorted(set(largest) - set(hosts), key=lambda q: -total[q]):
            d = {h: float(np.linalg.norm(at[h] - at[p])) for h in hosts}
            host = min(d, key=d.get, default=None)
            if host is not None and d[host] <= same_px:
                groups[host] += groups.pop(p)
            else:
                hosts.append(p)
    return [
        (largest[p][1], [c for q in group for c in owner.get(q, [])], p)
        for p, group in sorted(groups.items())
        if min_area_px <= sum(total[q] for q in group) <= max_area_px
    ]


def process_frame(
    image: np.ndarray,
    background: np.ndarray,
    params: VisionParams | None = None,
    *,
    to_mm=None,
    keep_masks: bool = False,
    hand_likely: bool = False,
) -> FrameResult:
    """Run the whole pipeline on one frame against a background image (uint8 or float).
    ``hand_likely``: the frame before had a hand (``body_parts``' hint; the same result)."""
    p = params or VisionParams()
    img = check_frame(image, p.shape)
    bg = np.asarray(background)
    if bg.shape != img.shape:
        raise UserError(
            f"background: size {bg.shape[1]} x {bg.shape[0]} px does not match the frame "
            f"({img.shape[1]} x {img.shape[0]}); capture the background again"
        )
    fit_gain, fit_offset, noise = illumination(img, bg)
    changed = abs(fit_gain - 1.0) > p.illumination_tolerance or abs(fit_offset) > p.offset_tolerance
    gain, offset = fit_gain, fit_offset
    if abs(gain - 1.0) < 0.02 and abs(offset) < 1.5:  # within the noise: the fast path
        gain, offset = 1.0, 0.0
    if bg.dtype != np.uint8 and gain == 1.0 and offset == 0.0:
        bg = np.clip(bg + 0.5, 0, 255).astype(np.uint8)
    diff = subtract(img, bg, gain, offset)
    # thresholds: each hand's relative to the light it shows (``relative_body``), never
    # below what the noise measured in the fit allows
    noise_body = 4.0 * noise / max(p.smooth_px, 1) + 2.0
    noise_contact = 4.0 * noise / 3.0 + 2.0
    lo_s, hi_s = SCALE_RANGE if p.contact_level > 0 else (1.0, 1.0)
    body, parts = body_parts(  # the mask of the parts' window only
        diff,
        p.body_threshold,
        p.contact_level or 1.0,
        noise_body,
        p.smooth_px,
        (lo_s, hi_s),
        hand_likely=hand_likely,
    )
    # contacts only around the pixels above the lowest contact threshold (the rest of the
    # frame cannot reach it through the smoothing), each part at its own threshold
    contacts = []
    if parts is not None:
        contacts = part_contacts(diff, parts, p, noise_contact, hi_s, to_mm)
    max_area = p.max_hand_fraction * img.shape[0] * img.shape[1]
    ppm = p.scale_px_per_mm
    same_px = SAME_HAND_MM * ppm
    hands = hands_of(body, parts, contacts, p.min_hand_area_px, max_area, same_px)
    if not hands and parts is not None:
        # parts, but none the size of a hand: a pointing hand hovers far dimmer than the
        # fingertip it touches with, and under dim light its palm's brightest block may
        # fall just short of a seed (its fingertip alone is left, too small for a hand);
        # look again with seeds nearer the noise floor (only frames that found no hand
        # pay for it: a frame with a hand, or an empty table, never does)
        body2, parts2 = body_parts(
            diff, p.body_threshold, p.contact_level or 1.0, noise_body, p.smooth_px,
            (lo_s, hi_s), hand_likely=True, seed_factor=DIM_SEED_FACTOR,
        )  # fmt: skip
        hands = hands_of(body2, parts2, contacts, p.min_hand_area_px, max_area, same_px)
        if hands:
            body, parts = body2, parts2
    found = []
    for main, mine, part in hands:
        got = analyse_hand(main, img.shape, p, diff, mine, to_mm)
        if got is not None:
            got[1].update(level=float(parts.peak[part]), light=float(parts.scale[part]))
            found.append(got)
    for _, e in found:
        e["px_per_mm"] = ppm
    clipped = touching = 0
    if found:  # the sensor's maximum on the hands' touching skin
        x0, y0, x1, y1 = parts.win
        if cv2.minMaxLoc(img[y0:y1, x0:x1])[1] >= 255:
            clipped, touching = clipped_share(
                img[y0:y1, x0:x1], touching_mask(img, diff, body, parts)
            )
    if len(found) > 1:  # largest first (a sort of one hand would still measure its area)
        found.sort(key=lambda he: -cv2.contourArea(he[0].contour_px.astype(np.float32)))
    touch = None
    if found:  # the touching skin, each region to the hand whose palm is nearest
        palms = [e["palm_px"] for _, e in found]
        touch = FrameTouch(diff, body, parts, ppm, palms, same_px)
    masks: Mapping[str, np.ndarray] = {}
    if keep_masks:  # the whole high-pass image only if someone looks at it
        sigma = p.highpass_sigma_px
        masks = Masks(
            {"diff": diff},
            {
                "body": functools.partial(full_body, body, parts, img.shape),
                "highpass": functools.partial(frame_highpass, diff, sigma),
                "foreground": functools.partial(foreground, parts, img.shape),
            },
        )
    return FrameResult(
        hands=tuple(h for h, _ in found),
        contacts=tuple(contacts),
        gain=float(fit_gain),
        offset=float(fit_offset),
        noise=float(noise),
        illumination_changed=bool(changed),
        clipped_px=int(clipped),
        touching_px=int(touching),
        masks=masks,
        extras=tuple(e for _, e in found),
        touch=touch,
        parts=parts,
    )
