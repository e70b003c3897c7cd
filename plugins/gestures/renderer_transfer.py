"""Cross-renderer transfer: a model trained on one renderer's images, tested on the
other's, under dimmer and brighter light, against the frames a decision is made from.

``transfer_rows(train, tests)`` fits the classifiers on the feature set ``train`` for
each decision window and reports, per test set, static, dynamic and static-vs-dynamic
accuracy and the test set's clipped share of touching skin.
``cross_renderer(...)`` renders the sets (``renderer_sets``: training sets with domain
randomisation, test sets at x0.7, x1.0, x1.3 of the renderer's light) both ways, and
ranks the features the renderers disagree on (``renderer_gap``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from .feature_set import FeatureSet, columns
from .model import GestureModel
from .renderer_gap import renderer_gap
from .renderer_sets import is_static, render_set
from .reports import clipping

LIGHTS = (0.7, 1.0, 1.3)
FRAMES = (2, 3, 4, 5, 6)
N_HARMONICS = 0  # Fourier magnitudes only describe flat hands now: none transfer best


def accuracies(labels: np.ndarray, pred: np.ndarray, kind_dynamic: np.ndarray) -> dict:
    """Static, dynamic and static-vs-dynamic accuracy of ``pred`` against ``labels``."""
    labels, pred = np.asarray(labels).astype(str), np.asarray(pred).astype(str)
    st = is_static(labels)

    def acc(m: np.ndarray) -> float | None:
        return round(float(np.mean(pred[m] == labels[m])), 4) if m.any() else None

    return {
        "static_accuracy": acc(st),
        "dynamic_accuracy": acc(~st),
        "kind_accuracy": round(float(np.mean(np.asarray(kind_dynamic) == ~st)), 4),
    }


def fit(fs: FeatureSet, n_frames: int, n_harmonics: int = N_HARMONICS, seed: int = 0):
    """The classifiers fitted on the whole set ``fs`` for the first ``n_frames`` frames."""
    xs, xd, xk, sc = columns(fs, n_harmonics, n_frames)
    return GestureModel.fit(
        xs, xd, xk, sc, fs.labels, n_harmonics=n_harmonics, n_frames=n_frames, seed=seed,
        groups=fs.subjects,
    )  # fmt: skip


def transfer_rows(
    train: FeatureSet,
    tests: Mapping[str, FeatureSet],
    frames: Sequence[int] = FRAMES,
    n_harmonics: int = N_HARMONICS,
) -> list[dict]:
    """One row per (test set, decision window): accuracies and the clipped share."""
    rows = []
    for k in frames:
        if k not in train.dynamic:
            continue
        model = fit(train, k, n_harmonics)
        for name, test in tests.items():
            if k not in test.dynamic:
                continue
            xs, xd, xk, _ = columns(test, n_harmonics, k)
            pred = model.predict(xs, xd, xk)
            clip = clipping(list(test.names), list(test.meta.get("clipped_share", [])))
            rows.append(
                {
                    "test": name,
                    "frames": k,
                    "n": len(test.labels),
                    **accuracies(test.labels, pred, model.kind(xk)),
                    "clipped_share_mean": round(clip["clipped_share_mean"], 4),
                    "samples_clipped_over": round(clip["samples_over"], 4),
                }
            )
    return rows


#: (trained on, tested on): each way between the twin and phalanx, and both onto the
#: silhouette renderer, which nothing is trained on (the held-out one)
PAIRS = (
    ("twin", "phalanx"),
    ("phalanx", "twin"),
    ("twin", "silhouette"),
    ("phalanx", "silhouette"),
)


def cross_renderer(
    subjects: int = 2,
    reps: int = 2,
    *,
    lights: Sequence[float] = LIGHTS,
    frames: Sequence[int] = FRAMES,
    seed: int = 0,
    sets: dict | None = None,
) -> dict:
    """Train on one renderer (domain-randomised), test on another at each light
    (``PAIRS``). ``sets``: a dict to keep the rendered feature sets in (reused if present)."""
    sets = {} if sets is None else sets

    def get(renderer: str, light: float, randomise: bool) -> FeatureSet:
        key = (renderer, light, randomise)
        if key not in sets:
            sets[key] = render_set(
                renderer, subjects, reps, light_scale=light, randomise=randomise, seed=seed
            )
        return sets[key]

    out: dict = {"subjects": subjects, "reps": reps, "n_harmonics": N_HARMONICS, "rows": []}
    for train_r, test_r in PAIRS:
        train = get(train_r, 1.0, True)
        tests = {f"x{k:g}": get(test_r, k, False) for k in lights}
        for row in transfer_rows(train, tests, frames):
            out["rows"].append({"train": train_r, "test_renderer": test_r, **row})
    # the features the two renderers disagree on most for the same gestures (x1.0)
    out["gap"] = renderer_gap(get("twin", 1.0, False), get("phalanx", 1.0, False), top=5)
    return out
