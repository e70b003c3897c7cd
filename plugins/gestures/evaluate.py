"""Features of a dataset (cached) and the cross-validated evaluation of the classifiers.

``extract`` runs the vision pipeline on every sample (the first frames only) and keeps,
for each decision window (the first k frames, ``FRAMES_LIST``), the static, motion
(kind) and dynamic features and the motion score, and the per-frame pipeline time
(``feature_set.FeatureSet``; the per-frame features are ``features``'). ``cross_validate``
trains inside each outer fold (hyper-parameters searched inside the training part only,
``selection``) and tests on the rest: ``2fold`` (stratified, as in the paper) or ``loso``
(leave one subject out); ``reports`` makes its report. Evaluation only: the live
classifier never imports this module.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from console.plugin_api import UserError, cached_arrays, entry_path
from console.plugin_api import cache_dir as console_cache_dir

from .dataset import load_dataset
from .dataset_checks import require_hands
from .feature_set import FeatureSet, columns
from .features import (
    FRAMES_LIST,
    N_HARMONICS_MAX,
    analysis_params,
    record_features,
    sample_records,
)
from .model import GestureModel
from .progress import CancelCheck, Progress, part, step
from .reports import clipping, fold_report, report, sample_clipped_share
from .selection import INNER_FOLDS, candidates, select_settings
from .vision import VisionParams

FEATURES_VERSION = 13  # bump when features change: old caches are ignored
#: the modules whose code makes the features: their source is part of the cache key, so a
#: change to any of them is never answered with features the old code computed
FEATURE_MODULES = (
    "background.py", "contacts.py", "dataset.py", "descriptors.py", "feature_set.py",
    "features.py", "hand_shape.py", "orientation.py", "physical.py", "segmentation.py",
    "touch.py", "vision.py",
)  # fmt: skip
DEFAULT_CV = "2fold"


def features_code() -> str:
    """A short hash of the feature code's source (``FEATURE_MODULES``)."""
    h = hashlib.sha256(str(FEATURES_VERSION).encode())
    here = Path(__file__).parent
    for name in FEATURE_MODULES:
        h.update((here / name).read_bytes())
    return h.hexdigest()[:8]


def vision_settings_id(params: VisionParams) -> str:
    """A short hash of the vision settings the features were made with."""
    return hashlib.sha256(repr(params).encode()).hexdigest()[:6]


def cache_dir() -> Path:
    """``gestures`` in HapTable's cache directory (``console.files.paths``)."""
    return console_cache_dir("gestures")


def _key(samples, params: VisionParams, frames: Sequence[int]) -> str:
    h = hashlib.sha256()
    h.update(
        json.dumps(
            [FEATURES_VERSION, features_code(), repr(params), list(frames), N_HARMONICS_MAX]
        ).encode()
    )
    for s in samples:
        h.update(s.name.encode())
        h.update(s.gesture.encode())
        h.update(s.subject.encode())
        for p in (*s.frame_paths[: max(frames)], s.background_path):
            if p is not None:
                st = p.stat()
                h.update(f"{p.name}:{st.st_size}:{st.st_mtime_ns}".encode())
    return h.hexdigest()


def _fallback_background(samples, size_px) -> np.ndarray:
    """No background.png anywhere: the per-pixel median of the samples' first frames
    (hands are in different places, so the median is close to the empty table)."""
    step = max(1, len(samples) // 60)
    firsts = [s.frames(limit=1, size_px=size_px)[0] for s in samples[::step]]
    return np.median(np.stack(firsts), axis=0).astype(np.uint8)


def extract(
    root: str | Path,
    params: VisionParams | None = None,
    *,
    frames_list: Sequence[int] = FRAMES_LIST,
    use_cache: bool = True,
    progress: Progress | None = None,
    cancelled: CancelCheck | None = None,
) -> FeatureSet:
    """Features of every sample of the dataset at ``root`` (cached by content), for the
    decision windows of ``frames_list`` no longer than the shortest sample (a window is
    the same length for every sample). ``progress(frac, msg)`` after each sample;
    ``cancelled()`` stops it (``Cancelled``)."""
    params = params or VisionParams(n_harmonics=N_HARMONICS_MAX)
    if params.n_harmonics != N_HARMONICS_MAX:
        params = replace(params, n_harmonics=N_HARMONICS_MAX)
    samples = load_dataset(root)
    shortest = min(len(s.frame_paths) for s in samples)
    frames_list = tuple(k for k in frames_list if k <= shortest)
    if not frames_list:
        short = min(samples, key=lambda s: len(s.frame_paths))
        raise UserError(
            f"{short.name}: {shortest} frame(s); a gesture is decided from at least 2 "
            "frames: record every sample with 2 or more"
        )
    size = (params.width_px, params.height_px)
    key = _key(samples, params, frames_list)
    cfile = entry_path(cache_dir(), "features", key) if use_cache else None

    def compute() -> dict:
        threads = cv2.getNumThreads()
        cv2.setNumThreads(1)  # the per-frame time is for one core
        try:
            fs = _extract(samples, params, frames_list, size, progress, cancelled)
        finally:
            cv2.setNumThreads(threads)
        fs.meta["root"] = str(root)
        fs.meta["vision_settings"] = vision_settings_id(params)
        fs.meta["features_code"] = features_code()
        return _arrays(fs)

    # the entry carries its key: another set's features (copied over this name), a
    # damaged or empty entry is logged, deleted and extracted again, never used
    arrays, _ = cached_arrays(
        cfile, key, compute, what="gesture feature cache entry", check=_feature_set
    )
    return _feature_set(arrays)


def _extract(samples, params, frames_list, size, progress, cancelled) -> FeatureSet:
    fallback = None
    names, labels, subjects, times, cpu, shares = [], [], [], [], [], []
    xs_all: dict[int, list] = {k: [] for k in frames_list}
    xk_all: dict[int, list] = {k: [] for k in frames_list}
    xd_all: dict[int, list] = {k: [] for k in frames_list}
    sc_all: dict[int, list] = {k: [] for k in frames_list}
    for i, s in enumerate(samples):
        step(None, cancelled, 0, "features")
        frames = s.frames(limit=max(frames_list), size_px=size)
        bg = s.background(size_px=size)
        if bg is None:
            if fallback is None:
                fallback = _fallback_background(samples, size)
            bg = fallback
        clip: list = []
        ppm = s.meta.get("px_per_mm")  # the camera's scale on the glass, if given
        sp = replace(params, px_per_mm=float(ppm)) if ppm else params
        recs = sample_records(frames, bg, sp, times, cpu, clip)
        shares.append(sample_clipped_share(clip))
        xs, xk, xd, sc = record_features(recs, frames_list, N_HARMONICS_MAX, s.fps)
        names.append(s.name)
        labels.append(s.gesture)
        subjects.append(s.subject)
        for k in frames_list:
            xs_all[k].append(xs[k])
            xk_all[k].append(xk[k])
            xd_all[k].append(xd[k])
            sc_all[k].append(sc[k])
        step(progress, None, (i + 1) / len(samples), f"features {i + 1}/{len(samples)} samples")
    return FeatureSet(
        names,
        np.array(labels),
        np.array(subjects),
        {k: np.array(v) for k, v in xs_all.items()},
        {k: np.array(v) for k, v in xk_all.items()},
        {k: np.array(v) for k, v in xd_all.items()},
        {k: np.array(v) for k, v in sc_all.items()},
        np.array(times),
        {"n_harmonics_max": N_HARMONICS_MAX, "clipped_share": shares},
        np.array(cpu),
    )


def clipping_report(fs: FeatureSet) -> dict:
    """The set's clipped touching skin (``reports.clipping``; per sample in
    ``fs.meta["clipped_share"]``)."""
    shares = fs.meta.get("clipped_share") or [0.0] * len(fs.names)
    return clipping(list(fs.names), shares)


def _arrays(fs: FeatureSet) -> dict:
    """A feature set as the arrays of a cache entry."""
    arrays = {
        "names": np.array(fs.names),
        "labels": fs.labels,
        "subjects": fs.subjects,
        "frame_s": fs.frame_s,
        "frame_cpu_s": fs.frame_cpu_s,
        "meta_json": fs.meta,
    }
    for k in fs.dynamic:
        arrays[f"static_{k}"] = fs.static[k]
        arrays[f"kind_{k}"] = fs.kind[k]
        arrays[f"dyn_{k}"] = fs.dynamic[k]
        arrays[f"score_{k}"] = fs.score[k]
    return arrays


def _feature_set(z: dict) -> FeatureSet:
    """The feature set of a cache entry's arrays (``KeyError`` when one is missing)."""
    ks = sorted(int(n[4:]) for n in z if n.startswith("dyn_"))
    if not isinstance(z["meta_json"], dict):
        raise UserError("key 'meta_json': not an object")
    return FeatureSet(
        [str(n) for n in z["names"]],
        z["labels"].astype(str),
        z["subjects"].astype(str),
        {k: z[f"static_{k}"] for k in ks},
        {k: z[f"kind_{k}"] for k in ks},
        {k: z[f"dyn_{k}"] for k in ks},
        {k: z[f"score_{k}"] for k in ks},
        z["frame_s"],
        dict(z["meta_json"]),
        z["frame_cpu_s"],
    )


CV_WORDS = {
    "2fold": "2-fold CV (stratified by gesture, subjects on both sides)",
    "loso": "leave-one-subject-out CV",
}


def procedure(
    cv: str, harmonics: Sequence[int], frames: Sequence[int], seed: int, meta: Mapping
) -> str:
    """The evaluation in one line, as both the CLI and the console print it: the outer
    folds, the harmonics and frames (fixed, or chosen inside each training part), the
    seed and the settings the features were made with."""

    def which(what: str, vals: Sequence[int]) -> str:
        if len(vals) == 1:
            return f"{what} {vals[0]}"
        return f"{what} chosen from {'/'.join(map(str, vals))} by {INNER_FOLDS}-fold inner CV"

    return (
        f"{CV_WORDS.get(cv, cv)}, {which('harmonics', harmonics)}, {which('frames', frames)}, "
        f"seed {seed}; vision settings {meta.get('vision_settings', '?')}, "
        f"feature code {meta.get('features_code', '?')}"
    )


def evaluation(
    dataset: str | Path,
    profile: object = None,
    *,
    cv: str = DEFAULT_CV,
    n_harmonics: int | None = None,
    n_frames: int | None = None,
    seed: int = 0,
    use_cache: bool = True,
    progress: Progress | None = None,
    cancelled: CancelCheck | None = None,
) -> tuple[FeatureSet, dict]:
    """The one evaluation procedure of a dataset (``haptable gestures eval`` and the
    console's Gestures panel both run it, with these defaults): features with the
    profile's vision settings (cached by content and code), refused without hands, then
    ``cross_validate`` with harmonics and frames chosen inside each training part
    unless given (frames up to the profile's ``[gestures] frames``). Returns the
    features and the report, whose ``procedure`` names all of it. Progress: features
    0-50 %, folds 50-100 %."""
    fs = extract(
        dataset,
        analysis_params(profile),
        use_cache=use_cache,
        progress=part(progress, 0.0, 0.5),
        cancelled=cancelled,
    )
    require_hands(fs, dataset)
    rep = cross_validate(
        fs,
        cv,
        n_harmonics=n_harmonics,
        n_frames=n_frames,
        max_frames=max_frames(profile),
        seed=seed,
        progress=part(progress, 0.5, 1.0),
        cancelled=cancelled,
    )
    rep["clipping"] = clipping_report(fs)
    return fs, rep


def max_frames(profile: object) -> int:
    """The profile's ``[gestures] frames`` (4 without a profile): the most frames a
    gesture is decided from."""
    if profile is None:
        return 4
    try:
        v = profile.get("gestures.frames")  # type: ignore[attr-defined]
    except Exception:
        return 4
    return 4 if v is None else int(v)


def splits(fs: FeatureSet, cv: str, seed: int = 0) -> list[tuple[np.ndarray, np.ndarray]]:
    from sklearn.model_selection import LeaveOneGroupOut, StratifiedKFold  # lazy: heavy

    idx = np.arange(len(fs.labels))
    if cv == "2fold":
        _, counts = np.unique(fs.labels, return_counts=True)
        if counts.min() < 2:
            raise UserError("--cv 2fold: every gesture needs at least 2 samples")
        return list(StratifiedKFold(2, shuffle=True, random_state=seed).split(idx, fs.labels))
    if cv == "loso":
        if len(np.unique(fs.subjects)) < 2:
            raise UserError("--cv loso: the dataset has one subject; use --cv 2fold")
        return list(LeaveOneGroupOut().split(idx, fs.labels, fs.subjects))
    raise UserError(f"--cv {cv!r}: use 2fold or loso")


def cross_validate(
    fs: FeatureSet,
    cv: str = "2fold",
    *,
    n_harmonics: int | None = 2,
    n_frames: int | None = 4,
    max_frames: int | None = None,
    seed: int = 0,
    progress: Progress | None = None,
    cancelled: CancelCheck | None = None,
    transfer: Mapping[str, FeatureSet] | None = None,
) -> dict:
    """Outer cross-validation of the whole classifier; the report the CLI prints (with
    ``folds``: the test size and accuracies of each outer fold). ``n_harmonics`` or
    ``n_frames`` None: chosen inside each outer fold's training part (nested CV; the
    choices are in ``folds``). ``progress(frac, msg)`` after each fold; ``cancelled()``
    stops it between folds (``Cancelled``).

    ``transfer``: feature sets of the same samples seen otherwise (the same performances
    under another light, say); each outer fold's model also classifies its test samples
    there, and ``transfer[name]`` in the report has that set's accuracies and its
    per-sample predictions (``predicted``)."""
    hs, frs = candidates(fs, n_harmonics, n_frames, max_frames)
    for h in hs:
        columns(fs, h, frs[0])  # a bad --harmonics / --frames is refused before any fit
    transfer = dict(transfer or {})
    for name, other in transfer.items():
        if list(other.names) != list(fs.names):
            raise UserError(f"transfer set {name}: not the same samples in the same order")
    pred_t = {name: np.empty(len(fs.labels), dtype=object) for name in transfer}
    pred = np.empty(len(fs.labels), dtype=object)
    thresholds = []
    folds = []
    chosen = []
    parts = splits(fs, cv, seed)
    for k, (tr, te) in enumerate(parts):
        step(progress, cancelled, k / len(parts), f"fold {k + 1}/{len(parts)}: training")
        sel = select_settings(fs, tr, hs, frs, seed=seed, cancelled=cancelled)
        h, f = sel["n_harmonics"], sel["n_frames"]
        xs, xd, xk, sc = columns(fs, h, f)
        m = GestureModel.fit(
            xs[tr], xd[tr], xk[tr], sc[tr], fs.labels[tr], n_harmonics=h, n_frames=f,
            seed=seed, groups=fs.subjects[tr],
        )  # fmt: skip
        thresholds.append(m.motion_threshold)
        pred[te] = m.predict(xs[te], xd[te], xk[te])
        for name, other in transfer.items():
            ts, td, tk, _ = columns(other, h, f)
            pred_t[name][te] = m.predict(ts[te], td[te], tk[te])
        folds.append(fold_report(fs, te, pred[te].astype(str), cv))
        folds[-1].update(n_harmonics=h, n_frames=f, selection=sel["scores"], svm=m.svm_settings())
        chosen.append((h, f))
        acc = folds[-1]["accuracy"]
        step(progress, None, (k + 1) / len(parts), f"fold {k + 1}/{len(parts)}: {acc:.1%}")
    h, f = max(set(chosen), key=chosen.count)  # the most frequent choice, for the summary
    rep = report(fs.labels, pred.astype(str), fs, cv, h, f, thresholds)
    rep = {"cv": cv, "procedure": procedure(cv, hs, frs, seed, fs.meta), **rep}
    rep["folds"] = folds
    rep["selection"] = {
        "searched": {"n_harmonics": list(hs), "n_frames": list(frs)},
        "chosen_per_fold": [{"n_harmonics": a, "n_frames": b} for a, b in chosen],
        "inner_folds": None if len(hs) * len(frs) == 1 else INNER_FOLDS,
    }
    if transfer:
        rep["transfer"] = {}
        for name, other in transfer.items():
            got = pred_t[name].astype(str)
            r = report(fs.labels, got, other, cv, h, f, thresholds)
            keys = ("static_accuracy", "dynamic_accuracy", "kind_accuracy", "n_samples")
            rep["transfer"][name] = {k: r[k] for k in keys} | {"predicted": got.tolist()}
    return rep


def train(
    fs: FeatureSet,
    *,
    n_harmonics: int | None = 2,
    n_frames: int | None = 4,
    max_frames: int | None = None,
    seed: int = 0,
    meta: dict | None = None,
    cancelled: CancelCheck | None = None,
) -> GestureModel:
    """The classifiers fitted on the whole feature set (``meta`` is added to the model's
    metadata); ``n_harmonics`` / ``n_frames`` None: chosen by cross-validation on the set
    (what was searched and each candidate's accuracy are kept in ``meta["selection"]``);
    ``cancelled()`` is checked before fitting."""
    hs, frs = candidates(fs, n_harmonics, n_frames, max_frames)
    for h in hs:
        columns(fs, h, frs[0])
    idx = np.arange(len(fs.labels))
    step(None, cancelled, 0, "training")
    sel = select_settings(fs, idx, hs, frs, seed=seed, cancelled=cancelled)
    h, f = sel["n_harmonics"], sel["n_frames"]
    xs, xd, xk, sc = columns(fs, h, f)
    selection = {
        "searched": {"n_harmonics": list(hs), "n_frames": list(frs)},
        "inner_cv_accuracy": sel["scores"],
    }
    model = GestureModel.fit(
        xs,
        xd,
        xk,
        sc,
        fs.labels,
        n_harmonics=h,
        n_frames=f,
        seed=seed,
        groups=fs.subjects,
        meta={
            "trained_on": fs.meta.get("root"),
            "n_samples": len(fs.labels),
            "selection": selection,
            **(meta or {}),
        },
    )
    selection["svm"] = model.svm_settings()
    return model
