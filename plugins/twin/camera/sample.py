"""Rendered samples with ground truth: ``render_sample(gesture, subject, rep, rng)``.

Ground truth of a sample: ``subject gesture hand fps rep kind ("static"|"dynamic")
variant ("in"/"out", "spread"/"pile", "cw"/"ccw" or "") rate hard t0_s mapping frames``;
each of ``frames`` holds ``t_s gesture illumination_step contacts_px contacts_mm`` and
``hands``: per hand ``subject side wrist_mm center_mm center_px angle_deg`` (fingers'
direction in the table frame, from +x towards +y) ``angle_px_deg`` (the same in the
displayed image, counter-clockwise from +x) ``palm_contact`` and ``contacts``: per
contact ``finger kind ("tip" | "knuckle": a curled finger resting on the glass) pos_mm
pos_px in_image``. A flat hand (closed/open hand, wipe) touches with the whole palm and
fingers: its ``tip`` contacts are the centres of the distal phalanges.

Hard cases the vision pipeline must survive are options (``hard=``):

- ``"empty"``: no hand at all (the table alone, the gesture label kept).
- ``"border_cut"``: the camera sees only part of the glass and the hand crosses the image
  border (contacts outside the image have ``in_image: false``).
- ``"two_hands"``: a second hand of the other side touches with one finger.
- ``"fingertip_only"``: only a small fingertip pad touches, the hand far above.
- ``"rotated_180"``: the hand points exactly along -y (180 degrees from the +y default),
  without tremor; pass ``angle_deg=`` for any other exact angle.
- ``"illumination_step"``: gain and offset jump at the middle frame.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from .geometry import TableMapping
from .gestures import DYNAMIC, GESTURES, STATIC, Take, plan_take, take_pose
from .hand import HandGeometry, HandPose, Subject, hand_pieces, make_subject
from .render import Rig, compose, hand_layer

HARD_CASES: tuple[str, ...] = (
    "empty",
    "border_cut",
    "two_hands",
    "fingertip_only",
    "rotated_180",
    "illumination_step",
)
STATIC_FRAMES = 6
DYNAMIC_FRAMES = 8
STEP_GAIN, STEP_OFFSET = 1.4, 25.0

#: A camera that sees only the middle of the glass (for the ``border_cut`` case).
ZOOMED_CORNERS_PX = ((790.0, 560.0), (-150.0, 548.0), (-140.0, -80.0), (780.0, -72.0))


def frame_truth(
    hands: list[tuple[Subject, HandPose]], mapping: TableMapping, label: str, t_s: float
) -> tuple[list, dict[str, Any]]:
    """Pieces to render and the per-frame ground truth of the posed hands."""
    geos = [hand_pieces(subject, pose) for subject, pose in hands]
    pieces = [p for geo in geos for p in geo.pieces]
    return pieces, frame_truth_of(geos, hands, mapping, label, t_s)


def frame_truth_of(
    geos: list[HandGeometry],
    hands: list[tuple[Subject, HandPose]],
    mapping: TableMapping,
    label: str,
    t_s: float,
) -> dict[str, Any]:
    """The per-frame ground truth of the posed ``hands`` (``geos``: their pieces)."""
    w, h = mapping.image_px
    out_hands = []
    for geo, (subject, pose) in zip(geos, hands, strict=True):
        c_px = mapping.mm_to_px([geo.center_mm])[0]
        fwd = np.array(geo.center_mm) + 50 * np.array(
            [np.cos(np.radians(pose.angle_deg)), np.sin(np.radians(pose.angle_deg))]
        )
        f_px = mapping.mm_to_px([fwd])[0]
        contacts = []
        for c in geo.contacts:
            p = mapping.mm_to_px([c["pos_mm"]])[0]
            contacts.append(
                {
                    "finger": c["finger"],
                    "kind": c["kind"],
                    "pos_mm": [round(c["pos_mm"][0], 3), round(c["pos_mm"][1], 3)],
                    "pos_px": [round(float(p[0]), 3), round(float(p[1]), 3)],
                    "in_image": bool(0 <= p[0] < w and 0 <= p[1] < h),
                }
            )
        out_hands.append(
            {
                "subject": subject.name,
                "side": pose.side,
                "wrist_mm": [round(pose.wrist_mm[0], 3), round(pose.wrist_mm[1], 3)],
                "center_mm": [round(geo.center_mm[0], 3), round(geo.center_mm[1], 3)],
                "center_px": [round(float(c_px[0]), 3), round(float(c_px[1]), 3)],
                "angle_deg": round(float(pose.angle_deg % 360), 4),
                # fingers' direction in the displayed image, counter-clockwise from +x
                "angle_px_deg": round(
                    float(np.degrees(np.arctan2(-(f_px[1] - c_px[1]), f_px[0] - c_px[0])) % 360),
                    4,
                ),
                "palm_contact": geo.palm_contact,
                "contacts": contacts,
            }
        )
    truth = {
        "t_s": round(t_s, 6),
        "gesture": label,
        "hands": out_hands,
        "contacts_px": [c["pos_px"] for hd in out_hands for c in hd["contacts"]],
        "contacts_mm": [c["pos_mm"] for hd in out_hands for c in hd["contacts"]],
    }
    return truth


def render_frame(
    hands: list[tuple[Subject, HandPose]],
    rig: Rig,
    t_s: float,
    rng: np.random.Generator,
    *,
    label: str = "",
    step: bool = False,
    noise: bool = True,
    blur_hands: tuple[list[tuple[Subject, HandPose]], ...] = (),
    light: float = 1.0,
) -> tuple[np.ndarray, dict[str, Any]]:
    """One uint8 frame of posed hands and its ground truth (of ``hands``). Motion blur:
    ``blur_hands`` are the same hands at other instants of the exposure, averaged in.
    ``light``: the sensor's exposure x gain (``compose``)."""
    pieces, truth = frame_truth(hands, rig.mapping, label, t_s)
    layer = hand_layer(pieces, rig.mapping)
    if blur_hands:
        for other in blur_hands:
            layer += hand_layer(frame_truth(other, rig.mapping, label, t_s)[0], rig.mapping)
        layer /= 1 + len(blur_hands)
    g, o = (STEP_GAIN, STEP_OFFSET) if step else (1.0, 0.0)
    img = compose(layer, rig, t_s, rng, step_gain=g, step_offset=o, noise=noise, light=light)
    return img, truth


def render_background(rig: Rig, t_s: float, rng: np.random.Generator) -> np.ndarray:
    """The empty table at time ``t_s`` (what a background capture would record)."""
    return render_frame([], rig, t_s, rng)[0]


def _as_subject(subject: str | Subject, seed: int) -> Subject:
    return subject if isinstance(subject, Subject) else make_subject(str(subject), seed)


def render_sample(
    gesture: str,
    subject: str | Subject,
    rep: int,
    rng: np.random.Generator,
    *,
    n_frames: int | None = None,
    fps: float = 60.0,
    rig: Rig | None = None,
    hard: tuple[str, ...] | frozenset[str] = (),
    side: str | None = None,
    wrist_mm: tuple[float, float] | None = None,
    angle_deg: float | None = None,
    t0_s: float | None = None,
    subject_seed: int = 0,
) -> tuple[np.ndarray, dict[str, Any]]:
    """Frames ``(n, H, W)`` uint8 of one gesture performance and its ground truth.

    The first frame shows the gesture already under way (contact made). ``t0_s`` is
    the session time of the first frame (ambient drift); drawn from ``rng`` if None.
    """
    if gesture not in GESTURES:
        raise ValueError(f"unknown gesture {gesture!r}; use one of {', '.join(GESTURES)}")
    bad = set(hard) - set(HARD_CASES)
    if bad:
        raise ValueError(f"unknown hard case(s) {sorted(bad)}; use {', '.join(HARD_CASES)}")
    rig = rig or Rig()
    subj = _as_subject(subject, subject_seed)
    n = n_frames or (STATIC_FRAMES if gesture in STATIC else DYNAMIC_FRAMES)
    t0 = float(rng.uniform(0, 600)) if t0_s is None else float(t0_s)
    table = rig.mapping.table_mm
    if "border_cut" in hard:
        rig = replace(rig, mapping=replace(rig.mapping, corners_px=ZOOMED_CORNERS_PX))
        if wrist_mm is None:
            # hand centre just inside the left image border, fingers pointing out of it
            edge = rig.mapping.px_to_mm([[15.0, 240.0 + rng.uniform(-120, 120)]])[0]
            angle_deg = 0.0 if angle_deg is None else angle_deg
            wrist_mm = (float(edge[0] - 0.5 * subj.length_mm), float(edge[1]))
    if "rotated_180" in hard and angle_deg is None:
        angle_deg = 270.0
    exact = "rotated_180" in hard or angle_deg is not None
    take = plan_take(
        gesture,
        subj,
        rng,
        table,
        side=side,
        wrist_mm=wrist_mm,
        angle_deg=angle_deg,
        duration_s=n / fps,
        tremor=not exact,
    )
    takes: list[Take] = [take]
    if "two_hands" in hard:
        other = "left" if take.side == "right" else "right"
        heading = take.angle_deg
        off = 130.0 * np.array([np.cos(np.radians(heading - 90)), np.sin(np.radians(heading - 90))])
        sign = 1.0 if other == "right" else -1.0
        w2 = np.asarray(take.wrist_mm) + sign * off
        takes.append(
            plan_take(
                "one_finger",
                subj,
                rng,
                table,
                side=other,
                wrist_mm=(float(w2[0]), float(w2[1])),
                angle_deg=heading,
            )
        )
    frames = np.empty((n, *rig.mapping.image_px[::-1]), np.uint8)
    truths = []
    for k in range(n):
        t = k / fps
        hands = [] if "empty" in hard else [(subj, take_pose(tk, t, rng)) for tk in takes]
        if "fingertip_only" in hard:
            hands = [(s, _fingertip_only(p)) for s, p in hands]
        step = "illumination_step" in hard and k >= n // 2
        blur: tuple = ()
        if rig.exposure_s > 0 and gesture in DYNAMIC and hands:  # the shutter is open
            e = rig.exposure_s  # from t - e/2 to t + e/2: the truth is at mid-exposure
            blur = tuple(
                [(subj, take_pose(tk, max(t + dt, 0.0))) for tk in takes] for dt in (-e / 2, e / 2)
            )
            if "fingertip_only" in hard:
                blur = tuple([(s, _fingertip_only(p)) for s, p in b] for b in blur)
        frames[k], tr = render_frame(
            hands, rig, t0 + t, rng, label=gesture, step=step, blur_hands=blur
        )
        tr["illumination_step"] = step
        truths.append(tr)
    truth = {
        "subject": subj.name,
        "gesture": gesture,
        "hand": take.side,
        "fps": fps,
        "rep": rep,
        "kind": "static" if gesture in STATIC else "dynamic",
        "variant": take.variant,
        "rate": round(take.rate, 4),
        "hard": sorted(hard),
        "t0_s": round(t0, 6),
        "mapping": rig.mapping.to_dict(),
        "frames": truths,
    }
    return frames, truth


def _fingertip_only(pose: HandPose) -> HandPose:
    high = 50.0
    return replace(pose, palm_h_mm=(high + 5, high), tip_radius_scale=0.35)


__all__ = [
    "DYNAMIC",
    "GESTURES",
    "HARD_CASES",
    "STATIC",
    "render_background",
    "render_frame",
    "render_sample",
]
