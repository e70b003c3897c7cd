"""Small gesture feature sets rendered in memory by either renderer (the camera twin or
the independent phalanx renderer), for cross-renderer checks without writing a dataset.

``render_set(renderer, subjects, reps, light_scale=..., randomise=...)`` renders every
(subject, gesture, rep), runs the vision pipeline on its frames and returns a
``FeatureSet`` (as ``evaluate.extract`` makes from a dataset on disk) with each sample's
clipped share of touching skin in ``meta["clipped_share"]``. ``randomise``: domain
randomisation as ``synth --randomise`` draws it (``augment.wide_condition``: light
x0.5-1.6 clipping at 255, LED lobes, defocus, gamma, read noise, hand size and finger
widths, hover heights, how gently a motion starts); the phalanx renderer gets the light,
the image-level part, the slow starts (``PHALANX_EASE_S`` x the condition's ``ease``)
and a rotate's pivot anywhere from the thumb's tip to the index's (``phalanx_style``).
Seeded per sample: the same seed at x0.7, x1.0 and x1.3 gives the same performances.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace
from functools import partial

import numpy as np

from console.plugin_api import UserError

from .dataset import GESTURES, STATIC
from .feature_set import FeatureSet
from .features import FRAMES_LIST, N_HARMONICS_MAX, record_features, sample_records
from .reports import sample_clipped_share
from .vision import VisionParams

RENDERERS = ("twin", "phalanx", "silhouette")
#: frames per sample (a decision is made from the first 2 .. 6)
N_FRAMES = 6
#: a randomised phalanx take's start from rest: this time constant (s) x the wide
#: condition's ``ease`` (0-1.3): 0-65 ms, a little beyond the twin's people (15-50 ms x
#: 0.7-1.3); without it every phalanx motion is at full speed from the first frame and a
#: model trained on them reads the twin's slow starts as static (dynamic 0.84 at 4 frames)
PHALANX_EASE_S = 0.05
_STYLE_KEY = 5381


def phalanx_style(seed: int, subject: int, gesture: int, rep: int, ease: float) -> dict:
    """A randomised phalanx take's motion style: ``ease_s`` (``PHALANX_EASE_S`` x the wide
    condition's ``ease``) and a rotate's ``pivot`` (0 thumb .. 1 index, uniform: people
    turn about the thumb, as the paper's knob gesture, or about the middle), drawn from
    its own seed so the takes' other draws stay as they were."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, subject, gesture, rep, _STYLE_KEY]))
    return {"ease_s": PHALANX_EASE_S * float(ease), "pivot": float(rng.uniform(0.0, 1.0))}


def _twin_samples(
    subjects: int,
    reps: int,
    seed: int,
    light_scale: float,
    randomise: bool,
    gestures: tuple[str, ...] = GESTURES,
) -> Iterator[tuple[str, str, np.ndarray, np.ndarray, float]]:
    from .augment import augment_sample, twin_profile, wide_condition, wide_subject  # lazy: twin
    from .synth import BACKGROUND_LEAD_S, _session_t0, _twin_camera, subject_names  # lazy: twin

    factory, profile = _twin_camera(seed, False, 0.0)
    plain = factory({**profile, "twin_camera.illumination": light_scale})
    sides = ["right"] * (subjects - 1) + ["left"] if subjects > 1 else ["right"]
    for si in range(subjects):
        name = subject_names(si + 1)[si]
        for gi, gesture in enumerate(GESTURES):
            if gesture not in gestures:
                continue
            for rep in range(reps):
                rng = np.random.default_rng(np.random.SeedSequence([seed, si, gi, rep]))
                t0 = _session_t0(si, gi, rep)
                kw = {"n_frames": N_FRAMES, "t0_s": t0, "side": sides[si], "subject_seed": seed}
                fps = 60.0
                if randomise:
                    cond = wide_condition(seed, si, gi, rep)
                    fps = float(cond["fps"])
                    cond["illumination"] = cond["illumination"] * light_scale
                    cam = factory({**profile, **twin_profile(cond)})
                    change = partial(wide_subject, hand=cond["hand"])
                    frames, _ = cam.render_sample(
                        gesture, name, rep, rng, subject_change=change, **kw
                    )
                    bg = cam.render_background(t0 - BACKGROUND_LEAD_S, rng)
                    frames, bg = augment_sample(frames, bg, cond["augment"], rng)
                else:
                    frames, _ = plain.render_sample(gesture, name, rep, rng, **kw)
                    bg = plain.render_background(t0 - BACKGROUND_LEAD_S, rng)
                yield name, gesture, frames, bg, fps


def _phalanx_samples(
    subjects: int,
    reps: int,
    seed: int,
    light_scale: float,
    randomise: bool,
    gestures: tuple[str, ...] = GESTURES,
) -> Iterator[tuple[str, str, np.ndarray, np.ndarray, float]]:
    from .augment import augment_sample, wide_condition  # lazy: images
    from .phalanx_gestures import FPS  # lazy: renderer
    from .phalanx_synth import _SAMPLE_KEY, optics_of, render_sample, subject_of  # lazy: renderer

    hands = ["right"] * (subjects - 1) + ["left"] if subjects > 1 else ["right"]
    for si in range(subjects):
        subject, optics = subject_of(seed, si, hands[si]), optics_of(seed, si)
        for gi, gesture in enumerate(GESTURES):
            if gesture not in gestures:
                continue
            for rep in range(reps):
                rng = np.random.default_rng(
                    np.random.SeedSequence([seed, si, gi, rep, _SAMPLE_KEY])
                )
                light, style = light_scale, {}
                cond = None
                if randomise:
                    cond = wide_condition(seed + 1, si, gi, rep)
                    light = cond["illumination"] * light_scale
                    style = phalanx_style(seed, si, gi, rep, cond["hand"]["ease"])
                frames, bg, _ = render_sample(
                    gesture, subject, optics, rng, n_frames=N_FRAMES, light_scale=light, **style
                )
                if cond is not None:
                    frames, bg = augment_sample(frames, bg, cond["augment"], rng)
                yield subject.name, gesture, frames, bg, FPS


def _silhouette_samples(
    subjects: int,
    reps: int,
    seed: int,
    light_scale: float,
    randomise: bool,
    gestures: tuple[str, ...] = GESTURES,
) -> Iterator[tuple[str, str, np.ndarray, np.ndarray, float]]:
    """The third renderer's samples (``silhouette_renderer``: held out, never trained
    on here, so ``randomise`` does not apply)."""
    from .silhouette_renderer import render_sample  # lazy: renderer

    for si in range(subjects):
        for gesture in GESTURES:
            if gesture not in gestures:
                continue
            for rep in range(reps):
                frames, bg, meta = render_sample(gesture, si, rep, light_scale, seed)
                yield str(meta["subject"]), gesture, frames, bg, float(meta["fps"])


def render_set(
    renderer: str,
    subjects: int = 3,
    reps: int = 2,
    *,
    light_scale: float = 1.0,
    randomise: bool = False,
    seed: int = 0,
    params: VisionParams | None = None,
    frames_list: tuple[int, ...] = FRAMES_LIST,
    gestures: tuple[str, ...] = GESTURES,
) -> FeatureSet:
    """Features of ``subjects`` x 10 gestures x ``reps`` samples rendered by
    ``renderer`` ("twin", "phalanx" or "silhouette") under ``light_scale`` times its light (only
    ``gestures``, each seeded as in the full set)."""
    if renderer not in RENDERERS:
        raise UserError(f"renderer {renderer!r}: use one of {', '.join(RENDERERS)}")
    if subjects < 1 or reps < 1:
        raise UserError(f"subjects {subjects}, reps {reps}: both must be at least 1")
    bad = [g for g in gestures if g not in GESTURES]
    if bad:
        raise UserError(f"gestures {bad}: unknown; use {', '.join(GESTURES)}")
    if not frames_list or not all(2 <= k <= N_FRAMES for k in frames_list):
        raise UserError(f"frames {list(frames_list)}: each must be from 2 to {N_FRAMES}")
    params = replace(params or VisionParams(), n_harmonics=N_HARMONICS_MAX)
    make = {
        "twin": _twin_samples,
        "phalanx": _phalanx_samples,
        "silhouette": _silhouette_samples,
    }[renderer]
    names, labels, subj, shares, cpu = [], [], [], [], []
    cols: dict[str, dict[int, list]] = {k: {f: [] for f in frames_list} for k in "skdc"}
    for i, (who, gesture, frames, bg, fps) in enumerate(
        make(subjects, reps, seed, light_scale, randomise, gestures)
    ):
        clip: list = []
        recs = sample_records(frames[: max(frames_list)], bg, params, cpu=cpu, clip=clip)
        parts = record_features(recs, frames_list, N_HARMONICS_MAX, fps)
        for key, got in zip("skdc", parts, strict=True):
            for f in frames_list:
                cols[key][f].append(got[f])
        names.append(f"{gesture}/{who}_{i:04d}")
        labels.append(gesture)
        subj.append(who)
        shares.append(sample_clipped_share(clip))
    arr = {k: {f: np.array(v) for f, v in d.items()} for k, d in cols.items()}
    meta = {
        "n_harmonics_max": N_HARMONICS_MAX,
        "clipped_share": shares,
        "renderer": renderer,
        "light_scale": light_scale,
        "randomise": randomise,
    }
    return FeatureSet(
        names, np.array(labels), np.array(subj), arr["s"], arr["k"], arr["d"], arr["c"],
        np.zeros(0), meta, np.array(cpu),
    )  # fmt: skip


def is_static(labels: np.ndarray) -> np.ndarray:
    """True for the static gestures' labels."""
    return np.isin(np.asarray(labels).astype(str), STATIC)
