"""A live twin camera's frames of a hand that keeps its shape and only moves rigidly.

A hand held on the glass (a resting hand in a demo, ``P`` on the Camera screen, a
static gesture) changes from frame to frame by its tremor alone, and the knob demo's
fingers turn the hand about the thumb's tip: both are ``HandPose.moved``, rigid moves of
one shape. Such a hand's pieces, contacts and grey levels are those of the same shape
moved, so ``CoherentFrames`` moves them instead of building the hand again: the pieces
and the ground truth exactly; the blurred layers of the skin above the glass by a warp
of the camera's pixels; the skin touching the glass (sharp, where the contacts are
found) is drawn anew at its place. The twin keeps a 60 frames a second camera on a
2-core machine that also runs the demo.

A small move (a tremor: ``MAX_SHIFT_MM``, ``MAX_TURN_DEG``) warps the last full render's
blurred layer by an affine map (drawn on nearly the frame's pixel grid: the closest
match). A larger one warps the shape's ``HandCanvas``: its blurred skin drawn once in the
hand's own frame at the camera's scale, put in place by the exact mapping hand frame ->
table -> camera (a homography, or a per-pixel map when the lens bends the image). A
frame is rendered in full when the shape is new (a finger, a height, the subject
changed; two hands). The warped skin differs from a full render by the resampling of
blurred edges drawn on another pixel grid (a canvas: another orientation), a blur that
follows the mapping's local scale (a few per cent across the glass), and blurred skin
just outside the image that a full render leaves out (``haptable bench twin-camera``
reports the error beside the speed: ``coherent_check``).
"""

from __future__ import annotations

import functools
from collections import OrderedDict
from dataclasses import dataclass, replace
from typing import Any

import cv2
import numpy as np

from .geometry import TableMapping
from .hand import HandGeometry, HandPose, Piece, Subject, hand_pieces
from .render import (
    LOW_RES,
    WARPABLE_SIGMA_PX,
    Rig,
    band_sigma_px,
    compose,
    hand_layer,
    split_rows,
)
from .sample import STEP_GAIN, STEP_OFFSET, frame_truth_of

#: the largest rigid move from the last full render its layer is warped for (a
#: tremor's few tenths); beyond (the knob's turn), the shape's canvas is
MAX_SHIFT_MM = 3.0
MAX_TURN_DEG = 2.0
#: shapes whose canvases a camera keeps (a demo loops over one or two)
KEPT_CANVASES = 4


def rigid(pose: HandPose) -> tuple[float, float, float]:
    """A pose's rigid part: wrist x, y (mm) and angle (degrees)."""
    return (float(pose.wrist_mm[0]), float(pose.wrist_mm[1]), float(pose.angle_deg))


def shape_of(pose: HandPose) -> HandPose:
    """A pose without its rigid part: equal for two poses one ``moved`` from the other."""
    return replace(pose, wrist_mm=(0.0, 0.0), angle_deg=0.0)


def _placement(pose: HandPose) -> np.ndarray:
    """3x3: the hand frame (the pose's shape at the origin) -> table mm for ``pose``."""
    x, y, t = rigid(pose)
    c, s = np.cos(np.radians(t)), np.sin(np.radians(t))
    return np.array([[c, -s, x], [s, c, y], [0.0, 0.0, 1.0]])


def motion(a: HandPose, b: HandPose):
    """The rigid motion (mm -> mm) taking pose ``a``'s hand to pose ``b``'s."""
    m = _placement(b) @ np.linalg.inv(_placement(a))

    def move(pts: Any) -> np.ndarray:
        p = np.asarray(pts, dtype=float).reshape(-1, 2)
        return p @ m[:2, :2].T + m[:2, 2]

    return move


def moved_geometry(
    geo: HandGeometry, a: HandPose, b: HandPose, keep: list[int] | None = None
) -> HandGeometry:
    """``hand_pieces(subject, b)`` from ``geo = hand_pieces(subject, a)`` when ``b`` is
    ``a`` moved rigidly (``HandPose.moved``): every point moved the same way (only the
    pieces numbered ``keep`` when given)."""
    move = motion(a, b)
    src = geo.pieces if keep is None else [geo.pieces[i] for i in keep]
    polys = [c for p in src for c in (p.poly_mm, *p.holes)]  # moved at once
    pieces = []
    if polys:
        at = split_rows(move(np.vstack(polys)), [len(c) for c in polys])
        for p in src:
            outline = next(at)
            pieces.append(Piece(outline, p.h_mm, p.refl, tuple(next(at) for _ in p.holes)))
    contacts = [{**c, "pos_mm": tuple(move(c["pos_mm"])[0])} for c in geo.contacts]
    tips = {f: (*move(t[:2])[0], t[2]) for f, t in geo.tips_mm.items()}
    center = tuple(move(geo.center_mm)[0])
    return HandGeometry(pieces, contacts, geo.palm_contact, center, tips)


def sharp_pieces(geo: HandGeometry, px_per_mm: float) -> list[int]:
    """The numbers of ``geo``'s pieces drawn sharp (the skin touching the glass: drawn
    anew each frame, the rest is warped)."""
    sigmas = [band_sigma_px(p.h_mm, px_per_mm) for p in geo.pieces]
    return [i for i, s in enumerate(sigmas) if s is not None and s < WARPABLE_SIGMA_PX]


def lit_box(layer: np.ndarray) -> tuple[int, int, int, int] | None:
    """(x0, y0, x1, y1): the box of ``layer``'s non-zero pixels, None when all dark."""
    cols, rows = np.flatnonzero(layer.any(axis=0)), np.flatnonzero(layer.any(axis=1))
    if not cols.size:
        return None
    return int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1


@dataclass(frozen=True)
class CanvasMapping:
    """Hand-frame mm -> canvas pixels: ``px_per_mm`` (the camera's) from ``origin_mm``;
    what ``render.hand_layer`` needs of a mapping."""

    origin_mm: tuple[float, float]
    scale: float
    image_px: tuple[int, int]

    def px_per_mm(self) -> float:
        return self.scale

    def mm_to_px(self, pts_mm: Any) -> np.ndarray:
        p = np.asarray(pts_mm, dtype=np.float64).reshape(-1, 2)
        return (p - self.origin_mm) * self.scale

    def px_to_frame(self) -> np.ndarray:
        """3x3: canvas pixels -> hand-frame mm."""
        (ox, oy), s = self.origin_mm, self.scale
        return np.array([[1 / s, 0.0, ox], [0.0, 1 / s, oy], [0.0, 0.0, 1.0]])


@functools.lru_cache(maxsize=2)
def _table_mm_of_pixels(mapping: TableMapping) -> np.ndarray:
    """(h, w, 2) float32: the table point every pixel sees (a bent lens's inverse, once)."""
    w, h = mapping.image_px
    yy, xx = np.mgrid[0:h, 0:w]
    grid = mapping.px_to_mm(np.column_stack([xx.ravel(), yy.ravel()])).reshape(h, w, 2)
    grid = grid.astype(np.float32)
    grid.setflags(write=False)
    return grid


class HandCanvas:
    """One hand shape's blurred skin drawn once in the hand's own frame (the shape at
    the origin, fingers along +x) at the camera's scale, padded by its blur; ``warp``
    puts it where a rigid pose of that shape shows in the camera."""

    def __init__(self, subject: Subject, pose: HandPose, mapping: TableMapping) -> None:
        self.pose = shape_of(pose)
        self.geo = hand_pieces(subject, self.pose)
        ppm = mapping.px_per_mm()
        self.sharp = sharp_pieces(self.geo, ppm)  # drawn anew each frame
        sigmas = [band_sigma_px(p.h_mm, ppm) for p in self.geo.pieces]
        blurred = [s for s in sigmas if s is not None and s >= WARPABLE_SIGMA_PX]
        self.layer: np.ndarray | None = None
        self.canvas: CanvasMapping | None = None
        if not blurred:
            return
        pad_mm = (3 * max(blurred) + 4 * LOW_RES) / ppm  # the blur's reach, both grids
        pts = np.vstack([p.poly_mm for p in self.geo.pieces])
        lo, hi = pts.min(axis=0) - pad_mm, pts.max(axis=0) + pad_mm
        size = np.ceil((hi - lo) * ppm).astype(int) + 1
        self.canvas = CanvasMapping((float(lo[0]), float(lo[1])), ppm, (int(size[0]), int(size[1])))
        layer = hand_layer(self.geo.pieces, self.canvas, "blurred")  # type: ignore[arg-type]
        box = lit_box(layer)
        if box is not None:
            x0, y0, x1, y1 = box
            self.layer, self._box = layer[y0:y1, x0:x1].copy(), box

    def warp(self, pose: HandPose, mapping: TableMapping) -> tuple[np.ndarray, tuple | None]:
        """(the blurred skin at ``pose`` in the camera's image, float32; the box it was
        drawn in (x0, y0, x1, y1), None when out of sight)."""
        w, h = mapping.image_px
        out = np.zeros((h, w), np.float32)
        if self.layer is None or self.canvas is None:
            return out, None
        bx, by = self._box[:2]
        # the kept crop's pixels -> hand frame -> table mm
        to_table = (
            _placement(pose)
            @ self.canvas.px_to_frame()
            @ np.array([[1.0, 0, bx], [0, 1.0, by], [0, 0, 1.0]])
        )
        ch, cw = self.layer.shape
        t = np.linspace(0.0, 1.0, 9)[:, None]  # the crop's outline (curved under a lens)
        edge = (
            np.vstack(
                [
                    np.hstack([t * cw, 0 * t]),
                    np.hstack([t * cw, 0 * t + ch]),
                    np.hstack([0 * t, t * ch]),
                    np.hstack([0 * t + cw, t * ch]),
                ]
            )
            - 0.5
        )
        mm = edge @ to_table[:2, :2].T + to_table[:2, 2]
        px = mapping.mm_to_px(mm)
        (x0, y0), (x1, y1) = np.floor(px.min(axis=0)) - 1, np.ceil(px.max(axis=0)) + 2
        x0, y0, x1, y1 = max(int(x0), 0), max(int(y0), 0), min(int(x1), w), min(int(y1), h)
        if x1 <= x0 or y1 <= y0:
            return out, None
        if not mapping.distorted:  # one homography: crop -> image
            m = mapping.homography @ to_table
            m = np.array([[1.0, 0, -x0], [0, 1.0, -y0], [0, 0, 1.0]]) @ m
            out[y0:y1, x0:x1] = cv2.warpPerspective(
                self.layer, m, (x1 - x0, y1 - y0), flags=cv2.INTER_LINEAR, borderValue=0.0
            )
        else:  # each pixel's table point back into the crop
            back = np.linalg.inv(to_table)[:2]
            at = cv2.transform(_table_mm_of_pixels(mapping)[y0:y1, x0:x1], back)
            out[y0:y1, x0:x1] = cv2.remap(
                self.layer,
                at,
                None,
                cv2.INTER_LINEAR,
                borderMode=cv2.BORDER_CONSTANT,
                borderValue=0.0,
            )
        return out, (x0, y0, x1, y1)


class CoherentFrames:
    """``render(hands, t_s, rng, ...)`` as ``sample.render_frame`` does, for a single hand
    whose shape the last full render had: a small move (a tremor) warps that render's
    blurred layer (its grid nearly the frame's: the closest match), a larger one (the
    knob's turn) the shape's canvas."""

    def __init__(self, rig: Rig) -> None:
        self.rig = rig
        self._kept: tuple[Subject, HandPose, HandGeometry, np.ndarray | None] | None = None
        self._sharp: list[int] = []  # the kept render's sharp pieces
        self._lit: tuple[int, int, int, int] | None = None  # the kept layer's lit box
        self._canvases: OrderedDict[tuple[Subject, HandPose], HandCanvas] = OrderedDict()
        self.drawn_box: tuple[int, int, int, int] | None = None  # where the last warp drew
        self.full = 0  # frames rendered in full
        self.warped = 0  # frames moved from the last full render
        self.turned = 0  # frames warped from a shape's canvas

    def _same_shape(self, subject: Subject, pose: HandPose) -> bool:
        if self._kept is None:
            return False
        k_subject, k_pose, _, _ = self._kept
        return k_subject == subject and shape_of(k_pose) == shape_of(pose)

    def _small_move(self, pose: HandPose) -> bool:
        assert self._kept is not None
        (xa, ya, ta), (xb, yb, tb) = rigid(self._kept[1]), rigid(pose)
        return np.hypot(xb - xa, yb - ya) <= MAX_SHIFT_MM and abs(tb - ta) <= MAX_TURN_DEG

    def _canvas(self, subject: Subject, pose: HandPose) -> HandCanvas:
        """The kept canvas of this hand's shape (drawn the first time it is asked for)."""
        key = (subject, shape_of(pose))
        canvas = self._canvases.get(key)
        if canvas is not None:
            self._canvases.move_to_end(key)
            return canvas
        canvas = self._canvases[key] = HandCanvas(subject, pose, self.rig.mapping)
        while len(self._canvases) > KEPT_CANVASES:
            self._canvases.popitem(last=False)
        return canvas

    def _warp(self, layer: np.ndarray, a: HandPose, b: HandPose) -> np.ndarray:
        """``layer`` (rendered for pose ``a``) as the camera sees the hand at ``b`` (a
        small move): the pixel motion of three points around the wrist (the mapping is
        smooth: affine over a hand's reach)."""
        move = motion(a, b)
        x, y, _ = rigid(a)
        src_mm = np.array([[x, y], [x + 80.0, y], [x, y + 80.0]])
        m = self.rig.mapping
        src = m.mm_to_px(src_mm).astype(np.float32)
        dst = m.mm_to_px(move(src_mm)).astype(np.float32)
        aff = cv2.getAffineTransform(src, dst)
        out = np.zeros_like(layer)
        if self._lit is None:  # nothing above the glass to move
            self.drawn_box = None
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
        self.drawn_box = (x0, y0, x1, y1)
        return out

    def layer_and_truth(
        self, hands: list[tuple[Subject, HandPose]], label: str, t_s: float
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """The grey levels the hands add (illumination 1) and the frame's ground truth."""
        mapping = self.rig.mapping
        if len(hands) == 1 and self._same_shape(*hands[0]):
            subject, pose = hands[0]
            k_subject, k_pose, k_geo, k_blurred = self._kept  # type: ignore[misc]
            if self._small_move(pose):
                if k_blurred is None:  # the hand came to rest: its blurred skin, once
                    k_blurred = hand_layer(k_geo.pieces, mapping, "blurred")
                    self._kept = (k_subject, k_pose, k_geo, k_blurred)
                    self._lit = lit_box(k_blurred)
                    self._sharp = sharp_pieces(k_geo, mapping.px_per_mm())
                geo = moved_geometry(k_geo, k_pose, pose, keep=self._sharp)
                blurred = self._warp(k_blurred, k_pose, pose)
                self.warped += 1
            else:  # turned or moved further: the shape's canvas
                canvas = self._canvas(subject, pose)
                geo = moved_geometry(canvas.geo, canvas.pose, pose, keep=canvas.sharp)
                blurred, self.drawn_box = canvas.warp(pose, mapping)
                self.turned += 1
            layer = hand_layer(geo.pieces, mapping, "sharp", over=blurred)
            return layer, frame_truth_of([geo], hands, mapping, label, t_s)
        # a new shape (or none, or two hands): rendered in one pass as the twin always
        # was; its geometry kept, its blurred layer made only if a next frame can use it
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
