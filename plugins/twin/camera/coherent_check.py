"""``CoherentFrames`` checked against full renders of the same poses with the same sensor
noise (the reference): a held hand's tremor, and the knob demo's hand turning about the
thumb's tip. Used by ``haptable bench twin-camera`` and the tests."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import replace
from typing import Any

import numpy as np

from .coherent import CoherentFrames
from .gestures import plan_take, take_pose
from .hand import HandPose, Subject, hand_pieces, make_subject
from .render import Rig, compose, hand_layer
from .sample import frame_truth, render_background
from .scripts import SequenceScript

#: the contacts a vision finds in a frame against a background: [(x, y) px, ...]
ContactsOf = Callable[[np.ndarray, np.ndarray], list]
Hands = list[tuple[Subject, HandPose]]

#: the knob demo's twin hand (``plugins/demos/script.py``): turning for 1.5 s at 60 fps,
#: then 0.5 s of empty table, looping
KNOB_TURN_FRAMES, KNOB_GAP_FRAMES = 90, 30


def frames_check(
    frames: Iterator[tuple[int, Hands, str]],
    rig: Rig,
    background: np.ndarray,
    contacts_of: ContactsOf | None = None,
) -> dict[str, Any]:
    """Each frame ``(k, hands, label)`` rendered both ways with the noise of seed ``k``:
    seconds and CPU seconds (all threads) per frame each way, the grey-level error, the
    ground truth's largest difference (px) and, given a vision (``contacts_of``), the
    largest gap between the contacts it finds in each frame; and the error of the hands'
    grey levels before light and noise (``render.hand_layer``'s)."""
    coh = CoherentFrames(rig)
    t_coh, t_full, c_coh, c_full, warped_at = [], [], [], [], []
    err, layer_err, truth_gap, contact_gap, counts_differ, n = [], [], 0.0, 0.0, 0, 0
    for k, hands, label in frames:
        n += 1
        before = coh.warped + coh.turned
        t0, c0 = time.perf_counter(), time.process_time()
        la, ta = coh.layer_and_truth(hands, label, k / 60)  # ``coh.render``, in two steps
        a = compose(la, rig, k / 60, np.random.default_rng(k))
        t1, c1 = time.perf_counter(), time.process_time()
        pieces, tb = frame_truth(hands, rig.mapping, label, k / 60)  # ``render_frame``
        lb = hand_layer(pieces, rig.mapping)
        b = compose(lb, rig, k / 60, np.random.default_rng(k))
        if coh.warped + coh.turned > before:
            warped_at.append(len(t_coh))
        t_coh.append(t1 - t0)
        c_coh.append(c1 - c0)
        t_full.append(time.perf_counter() - t1)
        c_full.append(time.process_time() - c1)
        err.append(np.abs(a.astype(np.int16) - b.astype(np.int16)))
        layer_err.append(np.abs(la - lb))
        pa, pb = np.array(ta["contacts_px"]), np.array(tb["contacts_px"])
        if pa.shape != pb.shape:
            truth_gap = np.inf
        elif pa.size:
            truth_gap = max(truth_gap, float(np.abs(pa - pb).max()))
        if contacts_of is None:
            continue
        ca = np.array(contacts_of(a, background), dtype=float).reshape(-1, 2)
        cb = np.array(contacts_of(b, background), dtype=float).reshape(-1, 2)
        if len(ca) != len(cb):
            counts_differ += 1
        elif len(ca):  # each contact's nearest in the other frame
            d = np.hypot(*(ca[:, None, :] - cb[None, :, :]).transpose(2, 0, 1))
            contact_gap = max(contact_gap, float(d.min(axis=1).max()), float(d.min(axis=0).max()))
    e, le = np.stack(err), np.stack(layer_err)
    return {
        "frames": n,
        "warped": coh.warped,  # moved from the last full render (a small move)
        "turned": coh.turned,  # warped from the shape's canvas (a larger move)
        "s_coherent": t_coh,
        "s_full": t_full,
        "cpu_s_coherent": c_coh,
        "cpu_s_full": c_full,
        "warped_frames": warped_at,  # which frames were warped (indices)
        "grey_error_mean": float(e.mean()),
        "grey_error_max": int(e.max()),
        "share_over_2_grey": float((e > 2).mean()),
        # the hands' grey levels before light and noise (illumination 1)
        "layer_error_rms": float(np.sqrt(np.mean(le.astype(np.float64) ** 2))),
        "layer_error_p999": float(np.percentile(le, 99.9)),
        "truth_gap_px": truth_gap,
        "contact_gap_px": contact_gap if contacts_of is not None else None,
        "contact_counts_differ": counts_differ if contacts_of is not None else None,
        "drawn_box": coh.drawn_box,  # where the last warp drew (x0, y0, x1, y1)
    }


def held_hand_check(
    gesture: str,
    frames: int,
    rig: Rig,
    seed: int = 0,
    center_mm: tuple | None = None,
    contacts_of: ContactsOf | None = None,
) -> dict[str, Any]:
    """A held static ``gesture``'s tremor frames (``frames_check``), the palm's centre at
    ``center_mm`` when given (a hand near the glass's edge)."""
    rng = np.random.default_rng(seed)
    subject = make_subject(f"s{seed % 5 + 1}")
    take = plan_take(gesture, subject, rng, rig.mapping.table_mm)
    if center_mm is not None:
        at = hand_pieces(subject, take_pose(take, 0.0)).center_mm
        take = replace(take, wrist_mm=tuple(np.add(take.wrist_mm, np.subtract(center_mm, at))))
    bg = render_background(rig, 0.0, np.random.default_rng(seed + 1))
    poses = ((k, [(subject, take_pose(take, 0.0, rng))], gesture) for k in range(frames))
    return frames_check(poses, rig, bg, contacts_of)


def knob_hand_check(
    frames: int,
    rig: Rig,
    seed: int = 0,
    subject: str = "s1",
    contacts_of: ContactsOf | None = None,
) -> dict[str, Any]:
    """The knob demo's twin hand (``rotate``, looping with its gaps) for ``frames``
    frames from the first turning one (``frames_check``; the gaps' empty frames too)."""
    script = SequenceScript(
        [("rotate", subject, None, KNOB_TURN_FRAMES)],
        table_mm=rig.mapping.table_mm,
        gap_frames=KNOB_GAP_FRAMES,
        seed=seed,
    )
    rng = np.random.default_rng(seed)
    bg = render_background(rig, 0.0, np.random.default_rng(seed + 1))

    def poses() -> Iterator[tuple[int, Hands, str]]:
        for k in range(KNOB_GAP_FRAMES, KNOB_GAP_FRAMES + frames):
            hands, label, _ = script.hands(k, k / 60, rng)
            yield k, hands, label

    return frames_check(poses(), rig, bg, contacts_of)
