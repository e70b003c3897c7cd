"""Which hand a touching finger is on, whether that hand is a left or a right one, and
which finger it is: the ``type_id`` of TUIO 2.0's ``/tuio2/ptr`` (0 unknown, 1-5 the
right index, middle, ring, little finger and thumb, 6-10 the left hand's).

Plain functions of arrays; the geometry is done in table millimetres seen from above
(+y 90 degrees counter-clockwise of +x, the camera twin's convention), so a mirrored
rear camera image does not swap the hands. Without a camera -> table mapping the image's
handedness is unknown: every finger stays type 0.

- ``owner``: a contact belongs to the hand whose outline contains it, else to the
  nearest one within ``NEAR_FRACTION`` of that hand's radius, else to none.
- ``hand_axes``: the palm centre and radius (the maximum of the distance transform of
  the filled outline) and the fingers' direction (opposite the wrist, the vision's
  ``Hand.angle_deg``), mapped to table mm; ``axis_fits``: the touching fingers must
  lie ahead of the palm, else that direction is wrong and the frame decides nothing.
- ``read_hand``: the hand's side, from the thumb's. The thumb stands out of the hand's side (a bump beside
  the palm when lifted, a long finger when it touches); the little finger's side is the
  palm's straight edge. Across the palm (``BAND``, palm radii along the fingers'
  direction) the outline reaches farther on the thumb's side: decided when one side
  reaches ``SIDE_MARGIN`` palm radii farther than the other. Else ``SIDE_MIN_CONTACTS``
  or more touching fingers decide when both sides' best finger labellings
  (``label_fingers``) differ by ``SIDE_MARGIN_COST``; else ``None`` (type 0).
- ``label_fingers``: the contacts' angles about the palm centre from the fingers'
  direction, signed towards the little finger, matched in order (thumb .. little, never
  two on one finger) to the fingers' usual angles (``TEMPLATE_DEG`` +- ``SPREAD_DEG``);
  a finger is named only when every labelling within ``CLEAR_COST`` of the best names it
  alike (else ``None``). A lone finger is taken for the index (pointing) a priori
  (``LONE_PRIOR_COST`` against each other finger), so it is the index when its angle fits
  the index's clearly better than the others'; touching fingers are taken for
  neighbours (``SKIP_COST`` for each finger lifted between two touching ones).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

FINGERS = ("thumb", "index", "middle", "ring", "little")
#: the TUIO 2.0 type ids: right index .. little, thumb = 1 .. 5; the left hand's + 5
_ORDER = ("index", "middle", "ring", "little", "thumb")
TYPE_IDS = {
    **{("right", f): 1 + i for i, f in enumerate(_ORDER)},
    **{("left", f): 6 + i for i, f in enumerate(_ORDER)},
}
NEAR_FRACTION = 0.25
BAND = (-1.0, 1.0)
SIDE_MARGIN = 0.3
SIDE_MARGIN_COST = 10.0
SIDE_MIN_CONTACTS = 3
#: the vision's fingers' direction is taken as wrong (nothing decided that frame) when a
#: contact lies this far behind the palm centre (palm radii, towards the wrist: no finger
#: reaches there) or the contacts' centroid lies more than ``CENTROID_DEG`` off it
BEHIND = -0.3
CENTROID_DEG = 55.0
#: each finger's angle about the palm centre (deg from the fingers' direction, + towards
#: the little finger) and its spread: the medians and spreads measured on the camera
#: twin's hands (subjects s1-s4, its anatomical hand model) through the vision, checked
#: on other subjects and seeds (``haptable bench tuio``, ``fingers``)
TEMPLATE_DEG = (-80.0, -14.0, 3.0, 17.0, 31.0)
SPREAD_DEG = (10.0, 8.0, 8.0, 8.0, 8.0)
#: how far the fingers' direction the vision gives may be off (deg): one offset shared
#: by all the hand's contacts
AXIS_DEG = 25.0
CLEAR_COST = 2.0
LONE_PRIOR_COST = 3.0
#: a finger lifted between two touching ones is rarer than touching neighbours: the cost
#: of each finger a labelling skips inside its span
SKIP_COST = 3.0

ToMm = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class HandAxes:
    """A hand's palm centre (mm), palm radius (mm) and the fingers' unit direction."""

    palm_mm: np.ndarray
    palm_r_mm: float
    forward: np.ndarray

    def to_hand(self, pts_mm: np.ndarray) -> np.ndarray:
        """Points (mm) -> ``(u, v)`` in palm radii: ``v`` along the fingers, ``u`` to
        their right seen from above (a right hand's little finger side)."""
        q = np.asarray(pts_mm, float).reshape(-1, 2) - self.palm_mm
        f = self.forward
        right = np.array([f[1], -f[0]])
        return np.column_stack([q @ right, q @ f]) / self.palm_r_mm


def type_id(side: str | None, finger: str | None) -> int:
    """The TUIO 2.0 pointer type id (0: unknown hand or finger)."""
    if side is None or finger is None:
        return 0
    return TYPE_IDS[side, finger]


def owner(point_px: Sequence[float], contours_px: Sequence[np.ndarray], radii_px) -> int | None:
    """The index of the hand a contact belongs to: the one whose outline contains it, or
    the nearest within ``NEAR_FRACTION`` of its radius; ``None`` if none."""
    import cv2  # lazy: OpenCV loads with the first hand

    best, best_d = None, -math.inf
    p = (float(point_px[0]), float(point_px[1]))
    for k, (c, r) in enumerate(zip(contours_px, radii_px, strict=True)):
        poly = np.asarray(c, np.float32).reshape(-1, 1, 2)
        if len(poly) < 3:
            continue
        d = cv2.pointPolygonTest(poly, p, True)  # > 0 inside
        if d >= -NEAR_FRACTION * float(r) and d > best_d:
            best, best_d = k, d
    return best


def palm_px(contour_px: np.ndarray) -> tuple[np.ndarray, float]:
    """The palm centre and radius (px): the maximum of the filled outline's distance
    transform."""
    import cv2  # lazy: OpenCV loads with the first hand

    c = np.asarray(contour_px, float).reshape(-1, 2)
    x0, y0 = np.floor(c.min(0)).astype(int) - 2
    w, h = np.ceil(c.max(0)).astype(int) - (x0, y0) + 3
    mask = np.zeros((int(h), int(w)), np.uint8)
    cv2.fillPoly(mask, [np.rint(c - (x0, y0)).astype(np.int32)], 255)
    d = cv2.distanceTransform(mask, cv2.DIST_L2, 3)
    _, r, _, loc = cv2.minMaxLoc(d)
    return np.array([loc[0] + x0, loc[1] + y0], float), float(r)


def hand_axes(contour_px: np.ndarray, angle_deg: float, to_mm: ToMm) -> HandAxes | None:
    """The hand's axes in table mm from its outline (px) and the vision's angle (the
    rotation that turns the wrist to the image bottom); ``None`` if degenerate."""
    if len(np.asarray(contour_px).reshape(-1, 2)) < 3:
        return None
    p, r = palm_px(contour_px)
    if r < 1.0:
        return None
    a = math.radians(angle_deg)
    fwd_px = np.array([math.sin(a), -math.cos(a)])  # opposite the wrist (image axes)
    q = np.asarray(to_mm(np.array([p, p + r * fwd_px])), float).reshape(-1, 2)
    f = q[1] - q[0]
    r_mm = float(np.hypot(*f))
    if not np.isfinite(r_mm) or r_mm <= 0:
        return None
    return HandAxes(q[0], r_mm, f / r_mm)


def outline_reach(outline_uv: np.ndarray) -> float:
    """How much farther the outline (palm radii) reaches to the left of the fingers'
    direction than to the right, across the palm (``BAND``): > 0 a right hand's thumb."""
    uv = np.asarray(outline_uv, float).reshape(-1, 2)
    band = uv[(uv[:, 1] >= BAND[0]) & (uv[:, 1] <= BAND[1]), 0]
    if len(band) < 3:
        return 0.0
    return float(-band.min() - band.max())


def axis_fits(contacts_uv: np.ndarray) -> bool:
    """Whether the touching fingers (hand frame) lie where fingers reach: none behind
    the palm (``BEHIND``), their centroid within ``CENTROID_DEG`` of the fingers' way."""
    uv = np.asarray(contacts_uv, float).reshape(-1, 2)
    if not len(uv):
        return True
    u, v = uv.mean(0)
    off = abs(math.degrees(math.atan2(u, v)))
    return bool(uv[:, 1].min() >= BEHIND and off <= CENTROID_DEG)


def _angles_deg(contacts_uv: np.ndarray, side: str) -> np.ndarray:
    uv = np.asarray(contacts_uv, float).reshape(-1, 2)
    w = uv[:, 0] if side == "right" else -uv[:, 0]  # + towards the little finger
    return np.degrees(np.arctan2(w, uv[:, 1]))


def _labellings(theta_deg: np.ndarray) -> list[tuple[float, tuple[int, ...]]]:
    """Every in-order labelling of the contacts (sorted thumb .. little) with its cost,
    cheapest first: the squared normalised angle errors after the best common offset
    (the axis' error, itself costed against ``AXIS_DEG``), plus the lone-finger prior."""
    t, s = np.array(TEMPLATE_DEG), np.array(SPREAD_DEG)
    out = []
    for slots in itertools.combinations(range(5), len(theta_deg)):
        idx = list(slots)
        r, w = theta_deg - t[idx], 1.0 / s[idx] ** 2
        off = float((w * r).sum() / (w.sum() + 1.0 / AXIS_DEG**2))
        cost = float((w * (r - off) ** 2).sum()) + (off / AXIS_DEG) ** 2
        if len(slots) == 1 and slots[0] != 1:
            cost += LONE_PRIOR_COST
        cost += SKIP_COST * (slots[-1] - slots[0] + 1 - len(slots))  # lifted in between
        out.append((cost, slots))
    out.sort()
    return out


def label_fingers(contacts_uv: np.ndarray, side: str) -> tuple[list[str | None], float]:
    """Each contact's finger (``FINGERS``, ``None`` when unclear) on a ``side`` hand, and
    the best labelling's cost; contacts in the hand frame (``HandAxes.to_hand``). More
    than five contacts: none is named."""
    theta = _angles_deg(contacts_uv, side)
    n = len(theta)
    if n == 0:
        return [], 0.0
    if n > 5:
        return [None] * n, math.inf
    order = np.argsort(theta, kind="stable")
    ranked = _labellings(theta[order])
    best = ranked[0][0]
    near = [slots for cost, slots in ranked if cost <= best + CLEAR_COST]
    names: list[str | None] = [None] * n
    for k, i in enumerate(order):
        picks = {slots[k] for slots in near}
        if len(picks) == 1:
            names[int(i)] = FINGERS[picks.pop()]
    return names, best


@dataclass(frozen=True)
class HandReading:
    """What one frame says of one hand: ``side`` ("right", "left" or ``None``), the
    evidence it came from ("outline", "fingers", "none"), the outline's reach difference
    (palm radii, ``outline_reach``), the contacts in the hand frame (``None`` without
    a camera -> table mapping or with an axis a contact contradicts) and their number."""

    side: str | None
    evidence: str
    reach: float
    contacts_uv: np.ndarray | None
    n: int

    def fingers(self, side: str | None) -> tuple[str | None, ...]:
        """Each contact's finger on a ``side`` hand (``None``: unknown)."""
        if side is None or self.contacts_uv is None or not len(self.contacts_uv):
            return (None,) * self.n
        return tuple(label_fingers(self.contacts_uv, side)[0])


def read_hand(
    contour_px: np.ndarray, angle_deg: float, contacts_px: np.ndarray, to_mm: ToMm | None
) -> HandReading:
    """Side of one hand and its contacts in its frame (outline and contacts in camera
    px, ``angle_deg`` the vision's ``Hand.angle_deg``)."""
    pts = np.asarray(contacts_px, float).reshape(-1, 2)
    axes = None if to_mm is None else hand_axes(contour_px, angle_deg, to_mm)
    if axes is None:
        return HandReading(None, "none", 0.0, None, len(pts))
    outline = axes.to_hand(np.asarray(to_mm(np.asarray(contour_px, float).reshape(-1, 2))))
    reach = outline_reach(outline)
    uv = axes.to_hand(np.asarray(to_mm(pts), float)) if len(pts) else np.zeros((0, 2))
    if len(uv) and not axis_fits(uv):  # the touching fingers say the axis is wrong
        return HandReading(None, "none", reach, None, len(uv))
    if abs(reach) >= SIDE_MARGIN:
        return HandReading("right" if reach > 0 else "left", "outline", reach, uv, len(uv))
    if len(uv) >= SIDE_MIN_CONTACTS:
        cost_r = label_fingers(uv, "right")[1]
        cost_l = label_fingers(uv, "left")[1]
        if abs(cost_r - cost_l) >= SIDE_MARGIN_COST:
            side = "right" if cost_r < cost_l else "left"
            return HandReading(side, "fingers", reach, uv, len(uv))
    return HandReading(None, "none", reach, uv, len(uv))
