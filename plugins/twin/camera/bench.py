"""``haptable bench twin-camera``: how fast the camera twin renders frames and samples."""

from __future__ import annotations

import os
import time
from typing import Any

import numpy as np

from console.plugin_api import Frame, machine_info, summarize_s

from .coherent_check import held_hand_check, knob_hand_check
from .gestures import GESTURES, STATIC, plan_take, take_pose
from .hand import make_subject
from .render import Rig
from .sample import render_background, render_frame, render_sample


def run(ctx: Any = None, quick: bool = False) -> dict:
    """Frame render time per gesture (p50/p99), a held hand's frames moved from its
    last full render and the knob demo's turning hand's frames warped from its shape's
    canvas, each against full renders (speed, CPU, grey-level error, the vision's contact
    gap) and sample render throughput (the twin's share of ``gestures synth``,
    extrapolated to the paper's 2000 samples)."""
    rig = Rig()
    render_sample("drag", "s1", 0, np.random.default_rng(0), rig=rig)  # warm caches
    reps = 2 if quick else 8
    per_gesture = {}
    all_s: list[float] = []
    cpu_s: list[float] = []
    for g in GESTURES:
        times = []
        for rep in range(reps):
            rng = np.random.default_rng(rep)
            subj = make_subject(f"s{rep % 5 + 1}")
            take = plan_take(g, subj, rng, rig.mapping.table_mm)
            for k in range(8):
                pose = take_pose(take, k / 60.0, rng)
                t0, c0 = time.perf_counter(), time.process_time()
                render_frame([(subj, pose)], rig, k / 60.0, rng, label=g)
                times.append(time.perf_counter() - t0)
                cpu_s.append(time.process_time() - c0)
        per_gesture[g] = summarize_s(times)
        all_s += times
    empty = []
    for k in range(20):
        t0 = time.perf_counter()
        render_frame([], rig, k / 60.0, np.random.default_rng(k))
        empty.append(time.perf_counter() - t0)

    # the twin's share of dataset synthesis (``gestures synth``): one performance and
    # its background per sample, as the synthesizer renders them (PNG writing and the
    # dataset layout are the gestures plugin's and are timed by its benchmark)
    sreps = 1 if quick else 4
    t0 = time.perf_counter()
    n_samples = 0
    for gi, g in enumerate(GESTURES):
        for rep in range(sreps):
            rng = np.random.default_rng([gi, rep])
            t_s = 6.0 * rep + 1.0
            render_sample(g, "s1", rep, rng, rig=rig, t0_s=t_s)
            render_background(rig, t_s - 0.5, rng)
            n_samples += 1
    per_sample_s = (time.perf_counter() - t0) / n_samples
    # a held hand on the live camera: frames moved from the last full render
    # (``coherent``) against full renders of the same poses, speed and error
    held, vision = {}, _vision_contacts(ctx)
    for i, g in enumerate(STATIC):
        got = held_hand_check(g, 10 if quick else 40, rig, seed=i, contacts_of=vision)
        held[g] = _check_row(got)
    # the knob demo's hand turning about the thumb's tip (warped from its shape's canvas)
    knob = {}
    for seed in range(1 if quick else 3):
        got = knob_hand_check(60 if quick else 150, rig, seed=seed, contacts_of=vision)
        knob[f"seed_{seed}"] = _check_row(got)
    cores = os.cpu_count() or 1
    return {
        "frame_render": summarize_s(all_s),
        # CPU time of this process (all threads): robust when other jobs load the machine
        "frame_render_cpu": summarize_s(cpu_s),
        "frame_render_empty_table": summarize_s(empty),
        "held_hand_frames": held,
        "knob_hand_frames": knob,
        "frame_render_per_gesture": per_gesture,
        "sample_render_one_process": {
            "samples": n_samples,
            "s_per_sample": round(per_sample_s, 4),
        },
        "render_2000_estimate_s": round(2000 * per_sample_s / cores, 1),
        "load_average_1min": os.getloadavg()[0],
        "machine": machine_info(),
        "quick": quick,
    }


def _check_row(got: dict) -> dict:
    """A ``coherent_check`` as a bench row: time and CPU (all threads) per frame both ways
    (warped: the frames that were; full: the reference's frames), and the errors."""
    warped = got["warped_frames"]
    return {
        "warped_frames": len(warped),
        "frames": got["frames"],
        "coherent": summarize_s([got["s_coherent"][i] for i in warped]),
        "full": summarize_s(got["s_full"]),
        "coherent_cpu": summarize_s([got["cpu_s_coherent"][i] for i in warped]),
        "full_cpu": summarize_s(got["cpu_s_full"]),
        "grey_error_mean": round(got["grey_error_mean"], 4),
        "grey_error_max": got["grey_error_max"],
        "share_over_2_grey": round(got["share_over_2_grey"], 5),
        "layer_error_rms": round(got["layer_error_rms"], 4),
        "vision_contact_gap_px": got["contact_gap_px"],
        "vision_contact_counts_differ": got["contact_counts_differ"],
    }


def _vision_contacts(ctx: Any):
    """The profile's classifier's contacts in a frame against a background (None
    without a profile: the held-hand rows then compare the renders only)."""
    if ctx is None:
        return None
    from console.plugin_api.runtime import open_classifier  # lazy: the runtime's import

    clf = open_classifier(ctx.profile, ctx.pm)

    def contacts(image: np.ndarray, background: np.ndarray) -> list:
        clf.set_background(background)
        res = clf.process(Frame(image=image, seq=0, t_capture_s=0.0, source="twin"))
        return [c.pos_px for c in res.contacts]

    return contacts
