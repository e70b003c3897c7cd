"""A live twin camera's frames from the last full render of a hand that only trembled.

A hand held on the glass (a resting hand in a demo, ``P`` on the Camera screen, a
static gesture) changes from frame to frame by its tremor alone: ``HandPose.moved``, a
rigid shift of a fraction of a millimetre and a turn of a fraction of a degree. Its
pieces, contacts and grey levels are those of the last full render moved the same way,
so ``CoherentFrames`` moves them instead of building the hand again: the pieces and the
ground truth exactly, the blurred layers of the skin above the glass by an affine warp of
the camera's pixels; the skin touching the glass (sharp, where the contacts are found)
is drawn anew at its moved place. The twin keeps a 60 frames a second camera on a 2-core
machine that also runs the demo.

A full render is made whenever anything else changed: the subject, a finger, a height,
a move of more than ``MAX_SHIFT_MM`` or ``MAX_TURN_DEG`` from the last full render, a
second hand. The warped layers differ from a full render by the warp's interpolation of
blurred edges (``haptable bench twin-camera`` reports the error beside the speed).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace
from typing import Any

import cv2
import numpy as np

from .gestures import plan_take, take_pose
from .hand import HandGeometry, HandPose, Piece, Subject, hand_pieces, make_subject
from .render import Rig, compose, hand_layer
from .sample import STEP_GAIN, STEP_OFFSET, frame_truth_of, render_background, render_frame

#: the largest rigid move from the last full render a frame is warped for (a tremor's
#: few tenths; beyond: the hand moved and is rendered anew)
MAX_SHIFT_MM = 3.0
MAX_TURN_DEG = 2.0


def rigid(pose: HandPose) -> tuple[float, float, float]:
    """A pose's rigid part: wrist x, y (mm) and angle (degrees)."""
    return (float(pose.wrist_mm[0]), float(pose.wrist_mm[1]), float(pose.angle_deg))


def shape_of(pose: HandPose) -> HandPose:
    """A pose without its rigid part: equal for two poses one ``moved`` from the other."""
    return replace(pose, wrist_mm=(0.0, 0.0), angle_deg=0.0)


def motion(a: HandPose, b: HandPose):
    """The rigid motion (mm -> mm) taking pose ``a``'s hand to pose ``b``'s."""
    (xa, ya, ta), (xb, yb, tb) = rigid(a), rigid(b)
    d = np.radians(tb - ta)
    rot = np.array([[np.cos(d), -np.sin(d)], [np.sin(d), np.cos(d)]])
    wa, wb = np.array([xa, ya]), np.array([xb, yb])

    def move(pts: Any) -> np.ndarray:
        p = np.asarray(pts, dtype=float).reshape(-1, 2)
        return (p - wa) @ rot.T + wb

    return move


def moved_geometry(geo: HandGeometry, a: HandPose, b: HandPose) -> HandGeometry:
    """``hand_pieces(subject, b)`` from ``geo = hand_pieces(subject, a)`` when ``b`` is
    ``a`` moved rigidly (``HandPose.moved``): every point moved the same way."""
    move = motion(a, b)
    polys = [c for p in geo.pieces for c in (p.poly_mm, *p.holes)]  # moved at once
    at = iter(np.split(move(np.vstack(polys)), np.cumsum([len(c) for c in polys])[:-1]))
    pieces = []
    for p in geo.pieces:
        outline = next(at)
        pieces.append(Piece(outline, p.h_mm, p.refl, tuple(next(at) for _ in p.holes)))
    contacts = [{**c, "pos_mm": tuple(move(c["pos_mm"])[0])} for c in geo.contacts]
    tips = {f: (*move(t[:2])[0], t[2]) for f, t in geo.tips_mm.items()}
    center = tuple(move(geo.center_mm)[0])
    return HandGeometry(pieces, contacts, geo.palm_contact, center, tips)


def lit_box(layer: np.ndarray) -> tuple[int, int, int, int] | None:
    """(x0, y0, x1, y1): the box of ``layer``'s non-zero pixels, None when all dark."""
    cols, rows = np.flatnonzero(layer.any(axis=0)), np.flatnonzero(layer.any(axis=1))
    if not cols.size:
        return None
    return int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1


class CoherentFrames:
    """``render(hands, t_s, rng, ...)`` as ``sample.render_frame`` does, reusing the
    last full render of a single hand whose pose moved only rigidly and by little."""

    def __init__(self, rig: Rig) -> None:
        self.rig = rig
        self._kept: tuple[Subject, HandPose, HandGeometry, np.ndarray] | None = None
        self._lit: tuple[int, int, int, int] | None = None  # the kept layer's lit box
        self.full = 0  # frames rendered in full
        self.warped = 0  # frames moved from the last full render

    def _reusable(self, subject: Subject, pose: HandPose) -> bool:
        if self._kept is None:
            return False
        k_subject, k_pose, _, _ = self._kept
        if k_subject is not subject or shape_of(k_pose) != shape_of(pose):
            return False
        (xa, ya, ta), (xb, yb, tb) = rigid(k_pose), rigid(pose)
        return np.hypot(xb - xa, yb - ya) <= MAX_SHIFT_MM and abs(tb - ta) <= MAX_TURN_DEG

    def _warp(self, layer: np.ndarray, a: HandPose, b: HandPose) -> np.ndarray:
        """``layer`` (rendered for pose ``a``) as the camera sees the hand at ``b``: the
        pixel motion of three points around the wrist (the mapping is smooth: affine
        over a hand's reach)."""
        move = motion(a, b)
        x, y, _ = rigid(a)
        src_mm = np.array([[x, y], [x + 80.0, y], [x, y + 80.0]])
        m = self.rig.mapping
        src = m.mm_to_px(src_mm).astype(np.float32)
        dst = m.mm_to_px(move(src_mm)).astype(np.float32)
        aff = cv2.getAffineTransform(src, dst)
        out = np.zeros_like(layer)
        if self._lit is None:  # nothing above the glass to move
            return out
        # only where the layer is lit, grown by the move (the rest stays dark): the
        # ROI's pixels from the whole layer, its edge replicated (an arm leaving it)
        h, w = layer.shape
        grow = int(np.ceil(np.abs(dst - src).max())) + 2
        x0, y0, x1, y1 = self._lit
        x0, y0, x1, y1 = max(x0 - grow, 0), max(y0 - grow, 0), min(x1 + grow, w), min(y1 + grow, h)
        aff[:, 2] -= (x0, y0)
        out[y0:y1, x0:x1] = cv2.warpAffine(
            layer, aff, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
        )
        return out

    def layer_and_truth(
        self, hands: list[tuple[Subject, HandPose]], label: str, t_s: float
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """The grey levels the hands add (illumination 1) and the frame's ground truth."""
        mapping = self.rig.mapping
        if len(hands) == 1 and self._reusable(*hands[0]):
            subject, pose = hands[0]
            k_subject, k_pose, k_geo, k_blurred = self._kept
            if k_blurred is None:  # the hand came to rest: its blurred skin, once
                k_blurred = hand_layer(k_geo.pieces, mapping, "blurred")
                self._kept, self._lit = (k_subject, k_pose, k_geo, k_blurred), lit_box(k_blurred)
            geo = moved_geometry(k_geo, k_pose, pose)
            layer = hand_layer(
                geo.pieces, mapping, "sharp", over=self._warp(k_blurred, k_pose, pose)
            )
            self.warped += 1
            return layer, frame_truth_of([geo], hands, mapping, label, t_s)
        # a moving hand (or none, or two): rendered in one pass as the twin always was;
        # its geometry kept, its blurred layer made only if the next frame can use it
        geos = [hand_pieces(s, p) for s, p in hands]
        self._kept = (*hands[0], geos[0], None) if len(hands) == 1 else None
        self.full += 1
        layer = hand_layer([pc for g in geos for pc in g.pieces], mapping)
        return layer, frame_truth_of(geos, hands, mapping, label, t_s)

    def render(
        self,
        hands: list[tuple[Subject, HandPose]],
        t_s: float,
        rng: np.random.Generator,
        *,
        label: str = "",
        step: bool = False,
        noise: bool = True,
        light: float = 1.0,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """One uint8 frame and its ground truth (``sample.render_frame``'s)."""
        layer, truth = self.layer_and_truth(hands, label, t_s)
        g, o = (STEP_GAIN, STEP_OFFSET) if step else (1.0, 0.0)
        img = compose(
            layer, self.rig, t_s, rng, step_gain=g, step_offset=o, noise=noise, light=light
        )
        return img, truth


#: the contacts a vision finds in a frame against a background: [(x, y) px, ...]
ContactsOf = Callable[[np.ndarray, np.ndarray], list]


def held_hand_check(
    gesture: str,
    frames: int,
    rig: Rig,
    seed: int = 0,
    center_mm: tuple | None = None,
    contacts_of: ContactsOf | None = None,
) -> dict[str, Any]:
    """A held hand's tremor frames rendered both ways (``CoherentFrames`` and a full
    render, the reference) with the same sensor noise: seconds per frame each way, the
    grey-level error, the ground truth's largest difference and, given a vision
    (``contacts_of``), the largest gap between the contacts it finds in each frame
    (``bench twin-camera``, the tests)."""
    rng = np.random.default_rng(seed)
    subject = make_subject(f"s{seed % 5 + 1}")
    take = plan_take(gesture, subject, rng, rig.mapping.table_mm)
    if center_mm is not None:  # the palm's centre there (a hand near the glass's edge)
        at = hand_pieces(subject, take_pose(take, 0.0)).center_mm
        take = replace(take, wrist_mm=tuple(np.add(take.wrist_mm, np.subtract(center_mm, at))))
    bg = render_background(rig, 0.0, np.random.default_rng(seed + 1))
    coh = CoherentFrames(rig)
    t_coh, t_full, err, truth_gap, contact_gap, counts_differ = [], [], [], 0.0, 0.0, 0
    for k in range(frames):
        hands = [(subject, take_pose(take, 0.0, rng))]
        t0 = time.perf_counter()
        a, ta = coh.render(hands, k / 60, np.random.default_rng(k), label=gesture)
        t1 = time.perf_counter()
        b, tb = render_frame(hands, rig, k / 60, np.random.default_rng(k), label=gesture)
        t_coh.append(t1 - t0)
        t_full.append(time.perf_counter() - t1)
        err.append(np.abs(a.astype(np.int16) - b.astype(np.int16)))
        pa, pb = np.array(ta["contacts_px"]), np.array(tb["contacts_px"])
        truth_gap = max(truth_gap, float(np.abs(pa - pb).max()) if pa.size else 0.0)
        if contacts_of is None:
            continue
        ca = np.array(contacts_of(a, bg), dtype=float).reshape(-1, 2)
        cb = np.array(contacts_of(b, bg), dtype=float).reshape(-1, 2)
        if len(ca) != len(cb):
            counts_differ += 1
        elif len(ca):  # each contact's nearest in the other frame
            d = np.hypot(*(ca[:, None, :] - cb[None, :, :]).transpose(2, 0, 1))
            contact_gap = max(contact_gap, float(d.min(axis=1).max()), float(d.min(axis=0).max()))
    e = np.stack(err)
    return {
        "frames": frames,
        "warped": coh.warped,
        "s_coherent": t_coh,
        "s_full": t_full,
        "grey_error_mean": float(e.mean()),
        "grey_error_max": int(e.max()),
        "share_over_2_grey": float((e > 2).mean()),
        "truth_gap_px": truth_gap,
        "contact_gap_px": contact_gap if contacts_of is not None else None,
        "contact_counts_differ": counts_differ if contacts_of is not None else None,
        "lit_box": coh._lit,  # where the kept render's blurred skin lies (x0, y0, x1, y1)
    }
