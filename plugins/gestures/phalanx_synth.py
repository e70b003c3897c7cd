"""Gesture datasets from the independent phalanx renderer (``phalanx_renderer``).

``synth_phalanx(out, subjects, reps, light_scale=...)`` writes the dataset format
(``dataset.py``): per sample ``sample.json`` (subject, gesture, hand, fps; ``meta``:
``renderer: "phalanx"``, ``light_scale``, ``rep``, ``touch_clipped``), the frames, the
sample's own ``background.png`` and a ``truth.json``. Every sample is seeded from
(seed, subject, gesture, rep) and every subject's anatomy and light from (seed,
subject), independent of ``light_scale``: the same seed at 0.7, 1.0 and 1.3 gives the
same performances under dimmer or brighter light.
"""

from __future__ import annotations

import json
import os
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import UserError

from .dataset import GESTURES, STATIC, write_background, write_sample
from .phalanx_gestures import FPS, plan_take, take_poses
from .phalanx_renderer import (
    NAME,
    Optics,
    Subject,
    background,
    draw_optics,
    draw_subject,
    render,
    touch_mask,
)

STATIC_FRAMES = 6
DYNAMIC_FRAMES = 6
_SUBJECT_KEY, _OPTICS_KEY, _SAMPLE_KEY = 31337, 271828, 4099


def subject_of(seed: int, index: int, hand: str) -> Subject:
    """Subject ``index`` (0-based, named s1 ...) of the set made with ``seed``."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, index, _SUBJECT_KEY]))
    return draw_subject(f"s{index + 1}", hand, rng)


def optics_of(seed: int, index: int) -> Optics:
    """The light and sensor of subject ``index``'s session (-1: the dataset's own)."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, index + 1, _OPTICS_KEY]))
    return draw_optics(rng)


def render_sample(
    gesture: str,
    subject: Subject,
    optics: Optics,
    rng: np.random.Generator,
    *,
    n_frames: int | None = None,
    light_scale: float = 1.0,
    ease_s: float = 0.0,
    pivot: float = 0.5,
) -> tuple[np.ndarray, np.ndarray, dict]:
    """(frames, background, truth) of one performance; ``ease_s``: its motion starts
    from rest with this time constant (``phalanx_gestures.eased_s``); ``pivot``: a
    rotate's, from the thumb's tip (0) to the index's (1)."""
    n = n_frames or (STATIC_FRAMES if gesture in STATIC else DYNAMIC_FRAMES)
    take = replace(plan_take(gesture, subject, rng), ease_s=ease_s, pivot=pivot)
    poses = take_poses(take, subject, n, rng)
    frames = render(poses, subject, optics, light_scale, rng)
    bg = background(optics, light_scale, rng)
    mask = touch_mask(poses[0], subject)
    clipped = float((frames[0][mask] >= 255).mean()) if mask.any() else 0.0
    truth = {
        "renderer": NAME,
        "centre_px": [list(map(float, p.centre_px)) for p in poses],
        "angle_deg": [float(p.angle_deg) for p in poses],
        "speed": take.speed,
        "direction": take.direction,
        "touch_px": int(mask.sum()),
        "touch_clipped": round(clipped, 4),
    }
    return frames, bg, truth


def _job(job: dict) -> tuple[int, int, int]:
    """Render and write one (subject, gesture): (samples, frames, samples with clipping)."""
    seed, si, gi = job["seed"], job["subject"], job["gesture"]
    subject = subject_of(seed, si, job["hand"])
    optics = optics_of(seed, si)
    gesture = GESTURES[gi]
    frames_total = clipped = 0
    for rep in range(job["reps"]):
        rng = np.random.default_rng(np.random.SeedSequence([seed, si, gi, rep, _SAMPLE_KEY]))
        n = job["static_frames"] if gesture in STATIC else job["dynamic_frames"]
        frames, bg, truth = render_sample(
            gesture, subject, optics, rng, n_frames=n, light_scale=job["light_scale"]
        )
        extra = {
            "renderer": NAME,
            "source": NAME,
            "light_scale": job["light_scale"],
            "rep": rep,
            "touch_clipped": truth["touch_clipped"],
        }
        write_sample(
            job["out"],
            gesture,
            f"{subject.name}_{rep:03d}",
            frames,
            subject=subject.name,
            hand=subject.hand,
            fps=FPS,
            background=bg if job["per_sample_bg"] else None,
            truth=truth,
            extra=extra,
        )
        frames_total += len(frames)
        clipped += truth["touch_clipped"] > 0
    return job["reps"], frames_total, clipped


def synth_phalanx(
    out: str | Path,
    subjects: int = 5,
    reps: int = 40,
    *,
    seed: int = 0,
    workers: int | None = None,
    gestures: tuple[str, ...] = GESTURES,
    static_frames: int = STATIC_FRAMES,
    dynamic_frames: int = DYNAMIC_FRAMES,
    per_sample_background: bool = True,
    left_handed: int = 1,
    light_scale: float = 1.0,
    force: bool = False,
    **_ignored: Any,
) -> dict[str, Any]:
    """Write a phalanx dataset to ``out``; returns a summary (also in ``synth.json``)."""
    out = Path(out)
    bad = [g for g in gestures if g not in GESTURES]
    if bad:
        raise UserError(f"gestures {bad}: unknown; use {', '.join(GESTURES)}")
    if subjects < 1 or reps < 1:
        raise UserError(f"--subjects {subjects} --reps {reps}: both must be at least 1")
    if not 0 <= left_handed <= subjects:
        raise UserError(f"--left-handed {left_handed}: must be from 0 to --subjects {subjects}")
    if not 0.1 <= light_scale <= 3.0:
        raise UserError(f"--light-scale {light_scale}: must be from 0.1 to 3")
    if static_frames < 2 or dynamic_frames < 4:
        raise UserError("frames: static samples need >= 2 frames, dynamic >= 4")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise UserError(f"{out}: folder is not empty; choose a new --out (or --force to add to it)")
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    write_background(out, background(optics_of(seed, -1), light_scale, np.random.default_rng(seed)))
    hands = ["right"] * (subjects - left_handed) + ["left"] * left_handed
    jobs = [
        {
            "out": str(out),
            "seed": seed,
            "subject": si,
            "hand": hands[si],
            "gesture": GESTURES.index(g),
            "reps": reps,
            "static_frames": static_frames,
            "dynamic_frames": dynamic_frames,
            "per_sample_bg": per_sample_background,
            "light_scale": float(light_scale),
        }
        for si in range(subjects)
        for g in gestures
    ]
    workers = max(1, min(workers or os.cpu_count() or 1, len(jobs)))
    if workers == 1:
        results = [_job(j) for j in jobs]
    else:
        with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as ex:
            results = list(ex.map(_job, jobs))
    samples = sum(r[0] for r in results)
    info = {
        "out": str(out),
        "renderer": NAME,
        "samples": samples,
        "frames": sum(r[1] for r in results),
        "clipped_samples": sum(r[2] for r in results),
        "clipped_share": round(sum(r[2] for r in results) / max(1, samples), 4),
        "subjects": [f"s{i + 1}" for i in range(subjects)],
        "hands": {f"s{i + 1}": h for i, h in enumerate(hands)},
        "gestures": list(gestures),
        "reps": reps,
        "seed": seed,
        "light_scale": light_scale,
        "static_frames": static_frames,
        "dynamic_frames": dynamic_frames,
        "workers": workers,
        "seconds": round(time.perf_counter() - t0, 2),
    }
    (out / "synth.json").write_text(json.dumps(info, indent=1) + "\n")
    return info


__all__ = ["render_sample", "subject_of", "optics_of", "synth_phalanx"]
