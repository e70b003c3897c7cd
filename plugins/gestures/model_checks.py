"""Checks of a loaded gesture model: its settings, each classifier's arrays against each
other, and their widths against the features the vision pipeline makes.

skops rebuilds objects from arrays it does not check; a model whose arrays disagree
(a scaler mean of the wrong length, support vectors of another width, NaN in them) would
fail deep inside scikit-learn or, worse, classify silently wrong. Every problem is a
one-line ``UserError`` naming the file, the classifier and the array.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import AT_CLI, AT_CONSOLE, Placed

from .features import (
    FRAMES_LIST,
    N_HARMONICS_MAX,
    record_features,
    select_dynamic,
    select_kind,
    select_static,
)
from .sketch import DYNAMIC, STATIC

#: classes each classifier may answer
CLASSES = {"static_svm": STATIC, "dynamic_svm": DYNAMIC, "kind_svm": ("static", "dynamic")}
RETRAIN = "train it again with `haptable gestures train`"
#: the same in the console (the Gestures panel opens from the Camera screen)
RETRAIN_HERE = "train it again: Camera (F2), g, then t"


def retrain(what: str) -> Placed:
    """A model that cannot be used: ``what``, and how to make a good one where the user
    is (the command at a shell, the Gestures panel's key in the console)."""
    return Placed(what, {AT_CLI: RETRAIN, AT_CONSOLE: RETRAIN_HERE})


def _int_in(s: dict, key: str, allowed: tuple[int, ...], p: Path) -> int:
    v = s.get(key)
    if isinstance(v, bool) or not isinstance(v, int) or v not in allowed:
        raise retrain(
            f"{p}: settings {key} = {v!r}: expected one of {', '.join(map(str, allowed))}"
        )
    return v


def check_settings(raw: Any, p: Path) -> dict[str, Any]:
    """The model's settings (a JSON string in the file), checked and normalised."""
    if not isinstance(raw, str):
        raise retrain(f"{p}: no settings (a JSON text) in the model")
    try:
        s = json.loads(raw)
    except (ValueError, RecursionError) as e:
        raise retrain(f"{p}: settings are not readable JSON ({e})") from None
    if not isinstance(s, dict):
        raise retrain(f"{p}: settings are not a JSON object")
    thr = s.get("motion_threshold")
    if isinstance(thr, bool) or not isinstance(thr, (int, float)) or not math.isfinite(thr):
        raise retrain(f"{p}: settings motion_threshold = {thr!r}: expected a number")
    meta = s.get("meta", {})
    if not isinstance(meta, dict):
        raise retrain(f"{p}: settings meta = {meta!r}: expected an object")
    return {
        "motion_threshold": float(thr),
        "n_harmonics": _int_in(s, "n_harmonics", (0, *range(2, N_HARMONICS_MAX + 1)), p),
        "n_frames": _int_in(s, "n_frames", tuple(FRAMES_LIST), p),
        "meta": meta,
    }


def _array(est: Any, attr: str, shape: tuple, where: str, p: Path, *, numeric=True) -> np.ndarray:
    """``est.attr`` as an array of ``shape`` (``None`` entries: any), finite if numeric."""
    a = getattr(est, attr, None)
    if not isinstance(a, np.ndarray):
        raise retrain(f"{p}: {where} has no array {attr}")
    ok = a.ndim == len(shape) and all(
        w is None or w == n for w, n in zip(shape, a.shape, strict=False)
    )
    if not ok:
        want = " x ".join("any" if w is None else str(w) for w in shape)
        raise retrain(
            f"{p}: {where} {attr} has shape {a.shape}, expected ({want}): the model's "
            f"arrays do not fit together"
        )
    if numeric:
        if not np.issubdtype(a.dtype, np.number):
            raise retrain(f"{p}: {where} {attr} holds {a.dtype}, not numbers")
        if not np.all(np.isfinite(a)):
            raise retrain(f"{p}: {where} {attr} holds values that are not finite")
    return a


def check_pipeline(name: str, pipe: Any, p: Path) -> int:
    """One classifier (StandardScaler + RBF SVC) checked; returns its input width."""
    from sklearn.pipeline import Pipeline  # lazy: scikit-learn is heavy
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    steps = getattr(pipe, "steps", None) if isinstance(pipe, Pipeline) else None
    kinds = [(n, type(e)) for n, e in steps or []]
    if kinds != [("scale", StandardScaler), ("svc", SVC)]:
        raise retrain(
            f"{p}: {name} is {type(pipe).__name__}, not the StandardScaler + SVC pipeline "
            f"`haptable gestures train` makes"
        )
    scale, svc = pipe.named_steps["scale"], pipe.named_steps["svc"]
    nf = getattr(scale, "n_features_in_", None)
    if isinstance(nf, bool) or not isinstance(nf, (int, np.integer)) or nf < 1:
        raise retrain(f"{p}: {name} scaler has no input width (n_features_in_)")
    nf = int(nf)
    for attr in ("mean_", "scale_"):
        _array(scale, attr, (nf,), f"{name} scaler", p)
    where = f"{name} svc"
    classes = _array(svc, "classes_", (None,), where, p, numeric=False)
    unknown = sorted(set(map(str, classes)) - set(CLASSES[name]))
    if unknown or len(classes) < 2:
        raise retrain(
            f"{p}: {name} answers {', '.join(map(repr, unknown)) or 'fewer than two classes'}"
            f"; it may answer {', '.join(CLASSES[name])}"
        )
    k = len(classes)
    sv = _array(svc, "support_vectors_", (None, nf), where, p)
    n_sv = sv.shape[0]
    n_support = _array(svc, "_n_support", (k,), where, p)
    if n_sv < 1 or int(n_support.sum()) != n_sv or np.any(n_support < 0):
        raise retrain(
            f"{p}: {where} _n_support {n_support.tolist()} does not add up to the "
            f"{n_sv} support vectors"
        )
    for attr in ("dual_coef_", "_dual_coef_"):
        _array(svc, attr, (k - 1, n_sv), where, p)
    for attr in ("intercept_", "_intercept_"):
        _array(svc, attr, (k * (k - 1) // 2,), where, p)
    gamma = getattr(svc, "_gamma", None)
    if not isinstance(gamma, (float, np.floating)) or not (math.isfinite(gamma) and gamma > 0):
        raise retrain(f"{p}: {where} gamma {gamma!r} is not a positive number")
    try:  # the last word: the classifier answers a row of its own width
        pipe.predict(np.zeros((1, nf)))
        pipe.decision_function(np.zeros((1, nf)))
    except Exception as e:  # noqa: BLE001 - whatever scikit-learn raises, one line
        raise retrain(f"{p}: {name} cannot classify ({type(e).__name__}: {e})") from None
    return nf


def check_classifiers(svms: dict[str, Any], p: Path) -> dict[str, int]:
    """Every classifier present checked; at least one of static and dynamic."""
    if svms.get("static_svm") is None and svms.get("dynamic_svm") is None:
        raise retrain(f"{p}: neither static_svm nor dynamic_svm in the model")
    return {n: check_pipeline(n, m, p) for n, m in svms.items() if m is not None}


def feature_widths(n_harmonics: int, n_frames: int) -> dict[str, int]:
    """Feature widths the vision pipeline makes for each classifier with these settings."""
    k = n_frames
    xs, xk, xd, _ = record_features([None] * k, (k,), N_HARMONICS_MAX)
    return {
        "static_svm": select_static(xs[k], n_harmonics, N_HARMONICS_MAX).shape[1],
        "dynamic_svm": select_dynamic(xd[k], n_harmonics, N_HARMONICS_MAX).shape[1],
        "kind_svm": select_kind(xk[k]).shape[1],
    }


def check_widths(model: Any, p: Path) -> None:
    """Each classifier takes as many features as the pipeline makes for the model's
    settings (a model trained on another feature set is refused, not run)."""
    want = feature_widths(model.n_harmonics, model.n_frames)
    for name, w in want.items():
        svm = getattr(model, name)
        nf = getattr(svm, "n_features_in_", None) if svm is not None else None
        if nf is not None and int(nf) != w:
            raise retrain(
                f"{p}: {name} takes {int(nf)} features but the vision pipeline makes {w} "
                f"(n_harmonics = {model.n_harmonics}, n_frames = {model.n_frames}): it was "
                f"trained on another feature set"
            )
