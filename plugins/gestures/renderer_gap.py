"""Which gesture features depend on the renderer: per feature, how far apart two
renderers put the same gesture (the two-sample Kolmogorov-Smirnov statistic, per
gesture, averaged), and how much a model trained on one renderer relies on the feature
(the share of its variance between the gestures on the training renderer: eta squared).

``feature_names`` names the columns the static and dynamic classifiers see
(``features.select_static`` / ``select_dynamic``); ``renderer_gap(a, b)`` ranks them.
"""

from __future__ import annotations

import numpy as np

from .feature_set import FeatureSet, columns
from .features import MAX_COUNT_CODE, desc_indices
from .physical import MOTION_NAMES, SHARE_PARTS, STATIC_NAMES
from .renderer_sets import is_static


def _harmonic_names(n: int, n_max: int) -> list[str]:
    ks = np.concatenate([np.arange(-n_max, 0), np.arange(2, n_max + 1)])
    m = len(ks)
    return [f"fourier|{ks[i % m]}|" for i in desc_indices(n, n_max, (2,))]


def feature_names(n_harmonics: int, n_max: int = 16) -> tuple[list[str], list[str]]:
    """(static columns, dynamic columns) as the classifiers see them."""
    counts = [f"count={k}" for k in range(MAX_COUNT_CODE + 1)]
    fourier = _harmonic_names(n_harmonics, n_max)
    static = [*fourier, *STATIC_NAMES, *counts]
    shares = [f"{name}_share" for name in SHARE_PARTS]
    return static, [*static, *MOTION_NAMES, *shares, "contact_zoom_log"]


def ks_statistic(a: np.ndarray, b: np.ndarray) -> float:
    """Two-sample Kolmogorov-Smirnov statistic: the largest gap between the empirical
    distribution functions of ``a`` and ``b`` (0: same, 1: disjoint)."""
    a, b = np.sort(np.asarray(a, float)), np.sort(np.asarray(b, float))
    if len(a) == 0 or len(b) == 0:
        return 0.0
    x = np.concatenate([a, b])
    fa = np.searchsorted(a, x, side="right") / len(a)
    fb = np.searchsorted(b, x, side="right") / len(b)
    return float(np.max(np.abs(fa - fb)))


def per_gesture_ks(xa: np.ndarray, la: np.ndarray, xb: np.ndarray, lb: np.ndarray) -> np.ndarray:
    """Per column: the KS statistic between the two sets' samples of each gesture,
    averaged over the gestures both have."""
    out = np.zeros(xa.shape[1])
    gestures = sorted(set(la) & set(lb))
    for g in gestures:
        ma, mb = la == g, lb == g
        out += [ks_statistic(xa[ma, j], xb[mb, j]) for j in range(xa.shape[1])]
    return out / max(1, len(gestures))


def separation(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Per column: how well it alone tells the gestures apart on one renderer, as the
    share of its variance that lies between the gestures' means (0: none, 1: all; the
    ANOVA eta squared): what a classifier trained there can rely on."""
    x = np.asarray(x, float)
    total = x.var(axis=0) * len(x)
    between = np.zeros(x.shape[1])
    for g in np.unique(y):
        m = y == g
        between += m.sum() * (x[m].mean(axis=0) - x.mean(axis=0)) ** 2
    return np.where(total > 1e-12, between / np.maximum(total, 1e-12), 0.0)


def renderer_gap(
    a: FeatureSet, b: FeatureSet, n_harmonics: int = 6, n_frames: int = 4, top: int = 8
) -> dict:
    """The features whose distribution differs most between sets ``a`` and ``b`` for
    the same gesture, static and dynamic: per column its KS statistic, the reliance of
    a model trained on ``a`` on it, and their product (the offenders: different and
    relied on), the ``top`` of each ranked."""
    names_s, names_d = feature_names(n_harmonics, int(a.meta.get("n_harmonics_max", 16)))
    xs_a, xd_a, _, _ = columns(a, n_harmonics, n_frames)
    xs_b, xd_b, _, _ = columns(b, n_harmonics, n_frames)
    la, lb = a.labels.astype(str), b.labels.astype(str)
    sa, sb = is_static(la), is_static(lb)
    out = {}
    for kind, names, xa, xb, ma, mb in (
        ("static", names_s, xs_a, xs_b, sa, sb),
        ("dynamic", names_d, xd_a, xd_b, ~sa, ~sb),
    ):
        ks = per_gesture_ks(xa[ma], la[ma], xb[mb], lb[mb])
        rel = separation(xa[ma], la[ma])
        rows = [
            {"feature": n, "ks": round(float(k), 3), "separation": round(float(r), 3),
             "offence": round(float(k * max(r, 0.0)), 4)}
            for n, k, r in zip(names, ks, rel, strict=True)
        ]  # fmt: skip
        out[kind] = {
            "by_ks": sorted(rows, key=lambda r: -r["ks"])[:top],
            "by_offence": sorted(rows, key=lambda r: -r["offence"])[:top],
        }
    return out
