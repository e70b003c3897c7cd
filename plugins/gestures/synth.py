"""Synthetic gesture datasets from the camera twin, and recording from any camera.

``synth(out, subjects=5, reps=40)`` writes the paper's set (5 subjects x 10 gestures x
40 repetitions = 2000 samples) in the dataset format (``dataset.py``). Every sample has
its own seed derived from (seed, subject, gesture, rep), so the result does not depend
on the number of worker processes or their order. Static samples get
``STATIC_FRAMES`` frames, dynamic ones ``DYNAMIC_FRAMES`` (a gesture is decided from
its first 2 to 6, the same number for every sample).
Each sample gets its own ``background.png`` (the empty table half a second before, so
the slow ambient drift matches; ``per_sample_background=False`` leaves only the dataset's
``background.png``) and a ``truth.json`` (contacts, hand centre, angle).

``exposure_ms`` > 0 smears moving hands over the shutter time (motion blur).
Subjects are ``s1 .. sN``; the last ``left_handed`` of them (default 1, as in the
paper's five-subject study) use their left hand, the others their right.

``vary=True`` draws a recording condition per subject and session (``sessions`` blocks
of the repetitions; ``CONDITION_RANGES``): IR light level +-40 % (stratified: the
subject-sessions share the range evenly, each at a random place in its own stratum),
the LED lobes and hot-spot layout, sensor read noise (per session), hand size and hover
height of lifted parts (per subject, times a smaller per-session change). Each sample's
``sample.json`` holds its ``session`` and ``condition``; the dataset's
``background.png`` is the default rig's, every sample has its own under its session's
light. ``light_scale`` multiplies every sample's light (the same performances, seen
under another light: the same seed and a scale of 0.7 or 1.3 make the light-shift sets).

``vary="wide"`` (domain randomisation, ``--randomise``) draws a condition per sample
instead, over wider ranges (``augment.WIDE_RANGES``): light x0.5-1.6 clipping at 255, LED
lobes and a smooth light field, read noise, hand size, finger widths, hover heights,
glass glow against skin, defocus, gamma, drift, frame rate and shutter time; the
twin renders what it models, ``augment`` changes the rendered images for the rest.

``record(camera, out, gesture, subject)`` records from any ``console.core.contracts.Camera``
into the same format (the twin acts the gesture out when asked).
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from functools import partial
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import UserError, load_plugins

from .augment import WIDE_RANGES, augment_sample, twin_profile, wide_condition, wide_subject
from .dataset import (
    DYNAMIC,
    GESTURES,
    STATIC,
    kind_of,
    next_sample_name,
    write_background,
    write_png,
    write_sample,
)
from .progress import CancelCheck, Progress, step

STATIC_FRAMES = 6
DYNAMIC_FRAMES = 8
BACKGROUND_LEAD_S = 0.5

#: Uniform ranges of the recording conditions ``vary=True`` draws (twin camera keys).
CONDITION_RANGES = {
    "illumination": (0.6, 1.4),  # per session: IR LED level, +-40 %
    "noise_sigma": (1.0, 3.5),  # per session: read noise, grey levels
    "hand_scale": (0.92, 1.08),  # per subject (on top of the subject's own size)
    "hover_scale": (0.7, 1.4),  # per subject: heights of lifted fingers and palm
    "session_scale": (0.97, 1.03),  # per session: hand size and hover times this
}


def condition(
    seed: int, subject: int, session: int, subjects: int = 1, sessions: int = 1
) -> dict[str, float | int]:
    """The seeded recording condition of ``subject``'s ``session`` (twin camera keys), one
    of ``subjects`` x ``sessions``: the light level is stratified over them (a seeded
    order of the strata, a random place in each)."""
    r = CONDITION_RANGES
    who = np.random.default_rng(np.random.SeedSequence([seed, subject, 7919]))
    hand, hover = who.uniform(*r["hand_scale"]), who.uniform(*r["hover_scale"])
    ses = np.random.default_rng(np.random.SeedSequence([seed, subject, session, 104729]))
    k = ses.uniform(*r["session_scale"], size=2)
    slots = max(subjects * sessions, subject * sessions + session + 1)
    stratum = np.random.default_rng(np.random.SeedSequence([seed, slots, 15485863])).permutation(
        slots
    )[subject * sessions + session]
    lo, hi = r["illumination"]
    light = lo + (hi - lo) * (stratum + ses.uniform()) / slots
    return {
        "illumination": round(float(light), 4),
        "noise_sigma": round(float(ses.uniform(*r["noise_sigma"])), 3),
        "led_seed": int(ses.integers(0, 2**31 - 1)),
        "hand_scale": round(float(hand * k[0]), 4),
        "hover_scale": round(float(hover * k[1]), 4),
    }


def subject_names(n: int) -> list[str]:
    return [f"s{i + 1}" for i in range(n)]


def _sample_seed(seed: int, subject: int, gesture: int, rep: int) -> np.random.SeedSequence:
    return np.random.SeedSequence([seed, subject, gesture, rep])


def _session_t0(subject: int, gesture: int, rep: int) -> float:
    """When in the recording session a sample starts (seconds): drift continuity."""
    return 3600.0 * subject + 300.0 * gesture + 6.0 * rep + 1.0


def _twin_camera(seed: int, lens_distortion: bool, exposure_ms: float) -> tuple[Any, dict]:
    """The registered ``twin`` camera's factory and the settings it renders with
    (``console.core.contracts.SimulatedCamera``); both pickle, so worker processes build it too."""
    factory = load_plugins(entrypoints=False).get("camera", "twin").factory
    return factory, {
        "twin_camera.seed": seed,
        "twin_camera.script": "idle",
        "twin_camera.realtime": False,
        "twin_camera.lens_distortion": lens_distortion,
        "twin_camera.exposure_ms": exposure_ms,
    }


def _render_job(job: dict, on_rep: Callable[[], None] | None = None) -> tuple[int, int]:
    """Render and write the samples of one (subject, gesture): returns (samples, frames).
    ``on_rep()`` is called before each repetition (it may raise to stop)."""
    out, seed, si, gi = job["out"], job["seed"], job["subject"], job["gesture"]
    sessions = job.get("sessions", 0)  # 0: no variation, the default rig
    cameras: dict[int, Any] = {}
    subject = subject_names(si + 1)[si]
    gesture = GESTURES[gi]
    n = job["static_frames"] if gesture in STATIC else job["dynamic_frames"]
    frames_total = 0
    for rep in range(job["reps"]):
        if on_rep is not None:
            on_rep()
        rng = np.random.default_rng(_sample_seed(seed, si, gi, rep))
        if job.get("wide"):
            frames_total += _render_wide(job, gesture, rep, n, rng)
            continue
        session = rep * sessions // job["reps"] if sessions else 0
        cond = condition(seed, si, session, job["subjects"], sessions) if sessions else None
        if job["light_scale"] != 1.0:
            cond = dict(cond or {"illumination": 1.0})
            cond["illumination"] = round(cond["illumination"] * job["light_scale"], 4)
        if session not in cameras:  # the registered twin camera's factory
            prof = dict(job["camera_profile"])
            prof.update({f"twin_camera.{k}": v for k, v in (cond or {}).items()})
            cameras[session] = job["camera"](prof)
        camera = cameras[session]
        t0 = _session_t0(si, gi, rep)
        frames, truth = camera.render_sample(
            gesture, subject, rep, rng, n_frames=n, t0_s=t0, subject_seed=seed, side=job["side"]
        )
        bg = camera.render_background(t0 - BACKGROUND_LEAD_S, rng) if job["per_sample_bg"] else None
        extra = {"rep": rep, "source": "twin", "variant": truth["variant"]}
        if cond is not None:
            extra.update(session=f"{subject_names(si + 1)[si]}/{session}", condition=cond)
        _write(out, gesture, subject, rep, frames, truth, bg, extra, job["light_scale"])
        frames_total += len(frames)
    return job["reps"], frames_total


def _write(out, gesture, subject, rep, frames, truth, bg, extra: dict, light_scale) -> None:
    """One rendered sample into the dataset (``write_sample``), its light scale noted."""
    if light_scale != 1.0:
        extra["light_scale"] = light_scale
    write_sample(
        out, gesture, f"{subject}_{rep:03d}", frames, subject=subject, hand=truth["hand"],
        fps=truth["fps"], background=bg, truth=truth, extra=extra,
    )  # fmt: skip


def _render_wide(job: dict, gesture: str, rep: int, n: int, rng: np.random.Generator) -> int:
    """Render and write one sample of ``vary="wide"``: its own seeded condition
    (``augment.wide_condition``), a twin camera built for it, the image-level changes
    applied to its frames and background. Returns the frames written."""
    si, gi = job["subject"], job["gesture"]
    subject = subject_names(si + 1)[si]
    cond = wide_condition(job["seed"], si, gi, rep)
    cond["illumination"] = round(cond["illumination"] * job["light_scale"], 4)
    camera = job["camera"]({**job["camera_profile"], **twin_profile(cond)})
    t0 = _session_t0(si, gi, rep)
    frames, truth = camera.render_sample(
        gesture, subject, rep, rng, n_frames=n, t0_s=t0, side=job["side"],
        subject_seed=job["seed"], subject_change=partial(wide_subject, hand=cond["hand"]),
    )  # fmt: skip
    bg = camera.render_background(t0 - BACKGROUND_LEAD_S, rng)
    frames, bg = augment_sample(frames, bg, cond["augment"], rng)
    extra = {"rep": rep, "source": "twin", "variant": truth["variant"], "condition": cond}
    extra["session"] = f"{subject}/wide"  # one per subject: each sample has its own light
    _write(job["out"], gesture, subject, rep, frames, truth, bg, extra, job["light_scale"])
    return len(frames)


def _size(n_bytes: float) -> str:
    return f"{n_bytes / 1e9:.1f} GB" if n_bytes >= 1e9 else f"{n_bytes / 1e6:.0f} MB"


def _duration(seconds: float) -> str:
    if seconds >= 5400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 60:.0f} min" if seconds >= 90 else f"{max(1, round(seconds))} s"


def estimate(
    subjects: int = 5,
    reps: int = 40,
    *,
    seed: int = 0,
    workers: int | None = None,
    gestures: tuple[str, ...] = GESTURES,
    static_frames: int = STATIC_FRAMES,
    dynamic_frames: int = DYNAMIC_FRAMES,
    lens_distortion: bool = False,
    per_sample_background: bool = True,
    exposure_ms: float = 0.0,
    **_ignored: Any,
) -> dict[str, Any]:
    """What ``synth`` with these arguments will take, from a measured cost: one static
    and one dynamic sample rendered and written here (into a temporary folder, removed)
    as ``synth`` does, then scaled to the whole set: ``bytes``, ``seconds`` (the camera
    built once per process, the samples spread over ``workers`` processes on the cores
    the machine's load leaves free), the
    counts and the measured cost per image (``image_s``, ``image_bytes``); ``text``
    says it in one line. Takes about a second."""
    import shutil
    import tempfile

    gestures = tuple(gestures)
    camera_factory, camera_profile = _twin_camera(seed, lens_distortion, exposure_ms)
    t0 = time.perf_counter()
    camera_factory(camera_profile)
    build_s = time.perf_counter() - t0
    kinds = {"static": static_frames, "dynamic": dynamic_frames}
    per_image: dict[str, tuple[float, float]] = {}
    tmp = Path(tempfile.mkdtemp(prefix="haptable-synth-estimate-"))
    try:  # the first render warms up (caches, imports): measured again, the faster kept
        for kind, group in (("static", STATIC), ("dynamic", DYNAMIC), ("static", STATIC)):
            g = next((g for g in gestures if g in group), group[0])
            n = kinds[kind] + (1 if per_sample_background else 0)
            job = {
                "out": str(tmp), "seed": seed, "subject": 0, "gesture": GESTURES.index(g),
                "reps": 1, "static_frames": static_frames, "dynamic_frames": dynamic_frames,
                "camera": camera_factory, "camera_profile": camera_profile,
                "per_sample_bg": per_sample_background, "side": "right", "sessions": 0,
                "subjects": 1, "light_scale": 1.0,
            }  # fmt: skip
            shutil.rmtree(tmp / g, ignore_errors=True)
            t0 = time.perf_counter()
            _render_job(job)  # the camera is built: cached in this process
            took = time.perf_counter() - t0
            written = sum(f.stat().st_size for f in (tmp / g).rglob("*.png"))
            cost = (took / n, written / n)
            per_image[kind] = min(per_image[kind], cost) if kind in per_image else cost
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    n_static = sum(g in STATIC for g in gestures)
    n_dyn = len(gestures) - n_static
    bg = 1 if per_sample_background else 0
    images = {
        "static": subjects * reps * n_static * (static_frames + bg),
        "dynamic": subjects * reps * n_dyn * (dynamic_frames + bg),
    }
    n_jobs = subjects * len(gestures)
    workers = max(1, min(workers or os.cpu_count() or 1, n_jobs))
    cpu_s = sum(images[k] * per_image[k][0] for k in images)
    n_bytes = sum(images[k] * per_image[k][1] for k in images)
    n_images = images["static"] + images["dynamic"]
    samples = subjects * reps * len(gestures)
    image_s = sum(images[k] * per_image[k][0] for k in images) / max(1, n_images)
    image_bytes = n_bytes / max(1, n_images)
    # the processes share the cores other work leaves free (the measurement above ran
    # on one core with that load), and each builds its camera once
    try:
        load = os.getloadavg()[0]
    except OSError:
        load = 0.0
    free = max(1.0, (os.cpu_count() or 1) - max(0.0, load - 1.0))
    seconds = build_s + cpu_s / min(workers, free)
    text = (
        f"{subjects} x {len(gestures)} x {reps} = {samples} samples ({n_images} images): "
        f"about {_size(n_bytes)} and {_duration(seconds)} with {workers} process(es) "
        f"(measured here: {image_s * 1e3:.0f} ms and {image_bytes / 1e3:.0f} kB per image)"
    )
    return {
        "samples": samples,
        "images": n_images,
        "bytes": int(n_bytes),
        "seconds": round(seconds, 1),
        "workers": workers,
        "image_s": image_s,
        "image_bytes": image_bytes,
        "text": text,
    }


def synth(
    out: str | Path,
    subjects: int = 5,
    reps: int = 40,
    *,
    seed: int = 0,
    workers: int | None = None,
    gestures: tuple[str, ...] = GESTURES,
    static_frames: int = STATIC_FRAMES,
    dynamic_frames: int = DYNAMIC_FRAMES,
    lens_distortion: bool = False,
    per_sample_background: bool = True,
    left_handed: int = 1,
    exposure_ms: float = 0.0,
    vary: bool | str = False,
    sessions: int = 2,
    light_scale: float = 1.0,
    force: bool = False,
    progress: Progress | None = None,
    cancelled: CancelCheck | None = None,
) -> dict[str, Any]:
    """Write a synthetic dataset; returns counts and the wall time. ``progress(frac,
    msg)`` as samples are written (per sample with one worker, per subject and gesture
    with several); ``cancelled()`` stops it with ``Cancelled`` (``synth_atomic`` then
    leaves no partial dataset)."""
    out = Path(out)
    bad = [g for g in gestures if g not in GESTURES]
    if bad:
        raise UserError(f"gestures {bad}: unknown; use {', '.join(GESTURES)}")
    if subjects < 1 or reps < 1:
        raise UserError(f"--subjects {subjects} --reps {reps}: both must be at least 1")
    if not 0 <= exposure_ms <= 1000:
        raise UserError(f"--exposure-ms {exposure_ms}: must be from 0 to 1000")
    if not 0 <= left_handed <= subjects:
        raise UserError(f"--left-handed {left_handed}: must be from 0 to --subjects {subjects}")
    wide = vary == "wide"
    if vary not in (True, False, "wide"):
        raise UserError(f"vary={vary!r}: use False, True (per session) or 'wide' (per sample)")
    if wide and not per_sample_background:
        raise UserError(
            "--randomise needs per-sample backgrounds (leave out --no-sample-background)"
        )
    if vary is True and not 1 <= sessions <= reps:
        raise UserError(f"--sessions {sessions}: must be from 1 to --reps {reps}")
    if static_frames < 2 or dynamic_frames < 4:
        raise UserError("frames: static samples need >= 2 frames, dynamic >= 4")
    if not 0.1 <= light_scale <= 3.0:
        raise UserError(f"--light-scale {light_scale}: must be from 0.1 to 3")
    if out.exists() and not out.is_dir():
        raise UserError(f"{out}: exists and is not a folder; choose another --out")
    if out.is_dir() and any(out.iterdir()) and not force:
        raise UserError(f"{out}: folder is not empty; choose a new --out (or --force to add to it)")
    out.mkdir(parents=True, exist_ok=True)
    camera_factory, camera_profile = _twin_camera(seed, lens_distortion, exposure_ms)
    camera = camera_factory(camera_profile)
    mapping = camera.mapping
    t_start = time.perf_counter()
    write_background(out, camera.render_background(0.0, np.random.default_rng(seed)))
    sides = ["right"] * (subjects - left_handed) + ["left"] * left_handed
    jobs = [
        {
            "out": str(out),
            "seed": seed,
            "subject": si,
            "gesture": GESTURES.index(g),
            "reps": reps,
            "static_frames": static_frames,
            "dynamic_frames": dynamic_frames,
            "camera": camera_factory,
            "camera_profile": camera_profile,
            "per_sample_bg": per_sample_background,
            "side": sides[si],
            "sessions": sessions if vary is True else 0,
            "wide": wide,
            "subjects": subjects,
            "light_scale": float(light_scale),
        }
        for si in range(subjects)
        for g in gestures
    ]
    workers = max(1, min(workers or os.cpu_count() or 1, len(jobs)))
    done = n_frames = 0
    total = len(jobs) * reps
    if workers == 1:
        for job in jobs:
            who = f"{subject_names(job['subject'] + 1)[-1]} {GESTURES[job['gesture']]}"
            k = 0

            def on_rep(who=who, base=done) -> None:
                nonlocal k
                step(progress, cancelled, (base + k) / total, f"{base + k}/{total} samples ({who})")
                k += 1

            s, f = _render_job(job, on_rep)
            done, n_frames = done + s, n_frames + f
    else:
        with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as ex:
            futures = [ex.submit(_render_job, job) for job in jobs]
            try:
                for fut in futures:
                    s, f = fut.result()
                    done, n_frames = done + s, n_frames + f
                    step(progress, cancelled, done / total, f"{done}/{total} samples")
            except BaseException:
                ex.shutdown(wait=True, cancel_futures=True)
                raise
    step(progress, None, 1.0, f"{done}/{total} samples")
    seconds = time.perf_counter() - t_start
    info = {
        "out": str(out),
        "samples": done,
        "frames": n_frames,
        "subjects": subject_names(subjects),
        "gestures": list(gestures),
        "reps": reps,
        "seed": seed,
        "static_frames": static_frames,
        "dynamic_frames": dynamic_frames,
        "lens_distortion": lens_distortion,
        "per_sample_background": per_sample_background,
        "hands": dict(zip(subject_names(subjects), sides, strict=True)),
        "exposure_ms": exposure_ms,
        "vary": vary,
        "sessions": sessions if vary is True else None,
        "condition_ranges": WIDE_RANGES if wide else CONDITION_RANGES if vary else None,
        "light_scale": light_scale,
        "mapping": mapping.to_dict(),
        "workers": workers,
        "seconds": round(seconds, 2),
    }
    (out / "synth.json").write_text(json.dumps(info, indent=1) + "\n")
    return info


def _read_frame(camera: Any, timeout_s: float) -> Any:
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        f = camera.read(min(0.1, timeout_s))
        if f is not None:
            return f
    raise UserError(
        f"camera gave no frame for {timeout_s:g} s; check `haptable doctor` and "
        "the [camera] section of the profile"
    )


def capture_background(camera: Any, n_frames: int = 15, timeout_s: float = 2.0) -> np.ndarray:
    """The empty table: the median of ``n_frames`` (the twin renders it directly)."""
    if hasattr(camera, "background"):
        return camera.background()
    imgs = [np.asarray(_read_frame(camera, timeout_s).image) for _ in range(n_frames)]
    return np.median(np.stack(imgs), axis=0).astype(np.uint8)


def record(
    camera: Any,
    out: str | Path,
    gesture: str,
    subject: str,
    *,
    hand: str = "right",
    frames: int | None = None,
    name: str | None = None,
    fps: float | None = None,
    background: np.ndarray | None = None,
    timeout_s: float = 2.0,
) -> Path:
    """Record ``frames`` frames of one gesture from ``camera`` into ``out``; returns the
    sample folder. The twin (it has ``perform``) acts the gesture out first."""
    if gesture not in GESTURES:
        raise UserError(f"--gesture {gesture!r}: unknown; use one of {', '.join(GESTURES)}")
    if hand not in ("left", "right"):
        raise UserError(f"--hand {hand!r}: must be left or right")
    if not subject or not str(subject).strip():
        raise UserError("--subject: give a name like s1")
    n = frames or (STATIC_FRAMES if gesture in STATIC else DYNAMIC_FRAMES)
    need = 1 if kind_of(gesture) == "static" else 4
    if n < need:
        raise UserError(f"--frames {n}: a {kind_of(gesture)} gesture needs at least {need}")
    out = Path(out)
    first = None
    if hasattr(camera, "perform"):
        first = camera.perform(
            gesture, subject, hand, max(n, 2 * DYNAMIC_FRAMES) if gesture in DYNAMIC else max(n, 10)
        )
    imgs = []
    while len(imgs) < n:
        f = _read_frame(camera, timeout_s)
        if first is not None and f.seq < first:
            continue
        imgs.append(np.asarray(f.image))
    status = camera.status() if hasattr(camera, "status") else {}
    fps = fps or status.get("nominal_fps") or status.get("fps") or 60
    if background is not None and background.shape != imgs[0].shape:
        raise UserError(
            f"background is {background.shape[1]} x {background.shape[0]} px but "
            f"the camera gives {imgs[0].shape[1]} x {imgs[0].shape[0]} px"
        )
    name = name or next_sample_name(out, gesture, subject)
    return write_sample(
        out,
        gesture,
        name,
        imgs,
        subject=str(subject),
        hand=hand,
        fps=fps,
        background=background,
        extra={"source": status.get("driver", "camera")},
    )


__all__ = ["capture_background", "estimate", "record", "synth", "write_png"]
