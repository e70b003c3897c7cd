"""Accuracy reports of the gesture classifiers: per outer fold and over a whole
evaluation (accuracies, per-class recall, confusion, the pipeline's frame times)."""

from __future__ import annotations

import numpy as np

from console.plugin_api import summarize_s

from .feature_set import FeatureSet
from .model import GESTURES
from .sketch import DYNAMIC, STATIC


def fold_report(fs: FeatureSet, test: np.ndarray, pred: np.ndarray, cv: str) -> dict:
    """One outer fold: what was tested (a subject under ``loso``) and its accuracies."""
    labels = fs.labels[test].astype(str)
    is_st = np.isin(labels, STATIC)
    out = {
        "n_test": int(len(test)),
        "accuracy": float(np.mean(pred == labels)),
        "static_accuracy": float(np.mean(pred[is_st] == labels[is_st])) if is_st.any() else None,
        "dynamic_accuracy": (
            float(np.mean(pred[~is_st] == labels[~is_st])) if (~is_st).any() else None
        ),
    }
    if cv == "loso":
        out["subject"] = str(fs.subjects[test][0])
    return out


def report(
    labels: np.ndarray,
    pred: np.ndarray,
    fs: FeatureSet,
    cv: str,
    n_harmonics: int,
    n_frames: int,
    thresholds: list[float],
) -> dict:
    """The whole evaluation's report: accuracies (static, dynamic, kind), per-class
    recall, confusion, the pipeline's frame times and the settings used."""
    labels = np.asarray(labels).astype(str)
    is_st = np.isin(labels, STATIC)
    is_dy = np.isin(labels, DYNAMIC)
    present = [g for g in GESTURES if g in set(labels)] + sorted(set(labels) - set(GESTURES))
    recall = {g: float(np.mean(pred[labels == g] == g)) for g in present}
    conf = {
        g: {
            p: int(np.sum((labels == g) & (pred == p)))
            for p in present
            if np.any((labels == g) & (pred == p))
        }
        for g in present
    }
    kind_ok = np.isin(pred, DYNAMIC) == is_dy
    t = summarize_s(fs.frame_s)
    c = summarize_s(fs.frame_cpu_s)
    return {
        "cv": cv,
        "n_samples": int(len(labels)),
        "subjects": sorted(set(fs.subjects.tolist())),
        "static_accuracy": float(np.mean(pred[is_st] == labels[is_st])) if is_st.any() else None,
        "dynamic_accuracy": float(np.mean(pred[is_dy] == labels[is_dy])) if is_dy.any() else None,
        "kind_accuracy": float(np.mean(kind_ok)),
        "per_class_recall": recall,
        "confusion": conf,
        "frame_ms_p50": t["p50_ms"],
        "frame_ms_p99": t["p99_ms"],
        "frame_cpu_ms_p50": c["p50_ms"],
        "frame_cpu_ms_p99": c["p99_ms"],
        "frames_timed": t["n"],
        "n_harmonics": n_harmonics,
        "n_frames": n_frames,
        "motion_threshold": float(np.median(thresholds)) if thresholds else None,
    }


#: a sample whose touching skin clips over this share is reported (``clipping``)
CLIP_WARN = 0.05


def sample_clipped_share(counts: list[tuple[int, int]]) -> float:
    """A sample's clipped share: its frames' clipped over touching pixels (0: none)."""
    clipped = sum(c for c, _ in counts)
    touching = sum(t for _, t in counts)
    return clipped / touching if touching else 0.0


def clipping(names: list[str], shares: list[float], warn: float = CLIP_WARN) -> dict:
    """Per set: the mean clipped share of touching skin, the share of samples over
    ``warn``, those samples (at most 5 named) and a one-line warning when any."""
    v = np.asarray(shares, float)
    over = [n for n, x in zip(names, v, strict=True) if x > warn]
    out = {
        "clipped_share_mean": float(v.mean()) if v.size else 0.0,
        "samples_over": float(len(over) / v.size) if v.size else 0.0,
        "threshold": warn,
    }
    if over:
        some = ", ".join(over[:5]) + (f" and {len(over) - 5} more" if len(over) > 5 else "")
        out["warning"] = (
            f"touching skin clips at 255 on over {warn:.0%} of its pixels in {len(over)}/"
            f"{v.size} samples ({some}): lower the IR exposure or gain (Camera screen: "
            "exposure) and record again"
        )
    return out
