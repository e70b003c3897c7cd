"""Model selection inside training, and a trained model checked on another dataset.

``select_settings`` picks the Fourier harmonics and the frames a dynamic gesture is
decided from by stratified cross-validation on the training samples only (the SVMs' C
and gamma are searched inside each fit, ``model.fit_svm``); ``cross_validate`` in
``evaluate`` calls it inside every outer fold, so the reported accuracy is a nested
cross-validation. ``evaluate_model`` applies a saved model to a whole dataset.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from console.plugin_api import UserError

from .feature_set import FeatureSet, columns
from .model import GestureModel, inner_splitter
from .progress import CancelCheck, step
from .reports import fold_report, report

#: Candidates searched when the harmonics / frames are not given.
HARMONICS_CANDIDATES = (2, 4, 6, 8)
FRAMES_CANDIDATES = (2, 3, 4)
INNER_FOLDS = 3


def candidates(
    fs: FeatureSet, harmonics: int | None, frames: int | None, max_frames: int | None = None
) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """The harmonics and frames to search: a given value alone, else the candidates
    (frames no more than ``max_frames``, the latency budget, and only those extracted)."""
    nmax = int(fs.meta.get("n_harmonics_max", 16))
    hs = (
        (harmonics,)
        if harmonics is not None
        else tuple(h for h in HARMONICS_CANDIDATES if h <= nmax)
    )
    if frames is not None:
        fr: tuple[int, ...] = (frames,)
    else:
        top = max_frames if max_frames is not None else max(FRAMES_CANDIDATES)
        fr = tuple(
            f for f in sorted(set(FRAMES_CANDIDATES) | {top}) if f <= top and f in fs.dynamic
        )
        if not fr:
            raise UserError(f"gestures.frames = {top}: features exist for {sorted(fs.dynamic)}")
    return hs, fr


def select_settings(
    fs: FeatureSet,
    idx: np.ndarray,
    harmonics: Sequence[int],
    frames: Sequence[int],
    *,
    seed: int = 0,
    cancelled: CancelCheck | None = None,
) -> dict:
    """The (harmonics, frames) with the best inner-CV accuracy on samples ``idx`` of
    ``fs`` (ties: fewer frames, then fewer harmonics, i.e. the faster and simpler model),
    with every candidate's accuracy. The inner folds keep each subject on one side
    (``model.inner_splitter``): settings that only suit the people they were tuned on
    are not chosen. One candidate: returned without fitting."""
    grid = [(h, f) for h in harmonics for f in frames]
    if len(grid) == 1:
        return {"n_harmonics": grid[0][0], "n_frames": grid[0][1], "scores": None}
    labels = fs.labels[idx].astype(str)
    groups = fs.subjects[idx]
    splitter = inner_splitter(labels, groups, INNER_FOLDS, seed)
    if splitter is None:
        raise UserError(
            "model selection: a gesture has fewer than 2 training samples to choose the "
            "harmonics and frames on; give --harmonics and --frames, or record more samples"
        )
    correct = {c: 0 for c in grid}
    for tr, te in splitter.split(idx, labels, groups):
        step(None, cancelled, 0, "model selection")
        tr, te = idx[tr], idx[te]
        # the kind SVM depends on the frames only: fitted once per window
        kinds: dict[int, object] = {}
        for h, f in grid:
            xs, xd, xk, sc = columns(fs, h, f)
            m = GestureModel.fit(
                xs[tr], xd[tr], xk[tr], sc[tr], fs.labels[tr], n_harmonics=h, n_frames=f,
                seed=seed, kind_svm=kinds.get(f), groups=fs.subjects[tr],
            )  # fmt: skip
            kinds[f] = m.kind_svm
            correct[(h, f)] += int(np.sum(m.predict(xs[te], xd[te], xk[te]) == fs.labels[te]))
    n = len(idx)
    best = max(grid, key=lambda c: (correct[c], -c[1], -c[0]))
    return {
        "n_harmonics": best[0],
        "n_frames": best[1],
        "scores": {f"h{h}_f{f}": correct[(h, f)] / n for h, f in grid},
    }


def evaluate_model(fs: FeatureSet, model: GestureModel, path: str) -> dict:
    """The eval report (same keys as ``cross_validate``) of ``model`` on every sample."""
    xs, xd, xk, _ = columns(fs, model.n_harmonics, model.n_frames)
    pred = model.predict(xs, xd, xk).astype(str)
    rep = report(
        fs.labels, pred, fs, "model", model.n_harmonics, model.n_frames, [model.motion_threshold]
    )
    rep = {
        "cv": rep["cv"],
        "procedure": (
            f"the model {path} (harmonics {model.n_harmonics}, frames {model.n_frames}) on "
            "every sample, no cross-validation; vision settings "
            f"{fs.meta.get('vision_settings', '?')}, feature code "
            f"{fs.meta.get('features_code', '?')}"
        ),
        **rep,
    }
    rep["model"] = str(path)
    rep["trained_on"] = model.meta.get("trained_on")
    rep["selection"] = model.meta.get("selection")
    rep["folds"] = [fold_report(fs, np.arange(len(fs.labels)), pred, "model")]
    return rep


def holdout(
    fs: FeatureSet,
    train_idx: np.ndarray,
    test_idx: np.ndarray,
    *,
    n_harmonics: int | None = None,
    n_frames: int | None = None,
    max_frames: int | None = None,
    seed: int = 0,
) -> dict:
    """Train on ``train_idx`` (settings chosen there, as ``train`` does) and test on
    ``test_idx``: the fold's report with the chosen harmonics and frames."""
    hs, frs = candidates(fs, n_harmonics, n_frames, max_frames)
    sel = select_settings(fs, train_idx, hs, frs, seed=seed)
    h, f = sel["n_harmonics"], sel["n_frames"]
    xs, xd, xk, sc = columns(fs, h, f)
    tr, te = train_idx, test_idx
    m = GestureModel.fit(
        xs[tr], xd[tr], xk[tr], sc[tr], fs.labels[tr], n_harmonics=h, n_frames=f, seed=seed,
        groups=fs.subjects[tr],
    )  # fmt: skip
    pred = m.predict(xs[te], xd[te], xk[te]).astype(str)
    return {**fold_report(fs, te, pred, "holdout"), "n_harmonics": h, "n_frames": f}


def condition_report(
    fs: FeatureSet,
    conditions: dict[str, dict],
    *,
    n_harmonics: int | None = None,
    n_frames: int | None = None,
    seed: int = 0,
) -> dict:
    """Leave-one-condition-out (each recording session of a ``synth --vary`` set tested
    by a model trained on the others) and light transfer (trained on sessions lit within
    +-15 % of nominal, tested on those lit <= x0.8 and >= x1.2). ``conditions``: sample
    name -> {"session", "condition"} (from ``sample.json``); None where there are none.
    ``n_harmonics`` / ``n_frames`` None: chosen on each training part."""
    kw = {"n_harmonics": n_harmonics, "n_frames": n_frames, "seed": seed}
    names = list(fs.names)
    if not all(n in conditions and conditions[n].get("condition") for n in names):
        return {"leave_one_condition_out": None, "light_transfer": None}
    session = np.array([conditions[n]["session"] for n in names])
    light = np.array([conditions[n]["condition"]["illumination"] for n in names])
    folds = []
    for s in sorted(set(session)):
        te = np.flatnonzero(session == s)
        folds.append({"session": str(s), "illumination": float(light[te][0]),
                      **holdout(fs, np.flatnonzero(session != s), te, **kw)})  # fmt: skip
    out: dict = {"leave_one_condition_out": _pooled(folds), "light_transfer": {}}
    out["leave_one_condition_out"]["folds"] = folds
    mid = np.flatnonzero(np.abs(light - 1.0) <= 0.15)
    for name, te in (
        ("dim", np.flatnonzero(light <= 0.8)),
        ("bright", np.flatnonzero(light >= 1.2)),
    ):
        if len(te) == 0 or len(np.unique(fs.labels[mid])) < len(np.unique(fs.labels)):
            out["light_transfer"][name] = None
            continue
        r = holdout(fs, mid, te, **kw)
        r["train_light"] = [float(light[mid].min()), float(light[mid].max())]
        r["test_light"] = [float(light[te].min()), float(light[te].max())]
        out["light_transfer"][name] = r
    return out


def _pooled(folds: list[dict]) -> dict:
    """Accuracies over all folds' test samples (weighted by their sizes)."""

    def mean(key: str) -> float | None:
        got = [(f[key], f["n_test"]) for f in folds if f.get(key) is not None]
        return sum(a * n for a, n in got) / sum(n for _, n in got) if got else None

    return {k: mean(k) for k in ("accuracy", "static_accuracy", "dynamic_accuracy")}
