"""Cross-renderer transfer: a model trained on one renderer's images, tested on the
other's, under dimmer and brighter light, against the frames a decision is made from.

``transfer_rows(train, tests)`` fits the classifiers on the feature set ``train`` for
each decision window and reports, per test set, static, dynamic and static-vs-dynamic
accuracy and the test set's clipped share of touching skin.
``cross_renderer(...)`` renders the sets (``renderer_sets``: a training set with domain
randomisation of the size a lab would train on, ``TRAIN_SIZE``, test sets at x0.7, x1.0,
x1.3 of the renderer's light, ``TEST_SIZE``) both ways, over worker processes, and ranks
the features the renderers disagree on (``renderer_gap``); its report says the time each
part took.
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
#: what a lab trains on: a randomised set of the paper's five subjects x 10 repetitions
#: (``synth --randomise --subjects 5 --reps 10``); each test set 3 subjects x 6 reps
TRAIN_SIZE = (5, 10)
TEST_SIZE = (3, 6)


def _render(job: tuple) -> tuple[tuple, FeatureSet, float]:
    """One set of ``cross_renderer`` (a worker process's job): its key, features, seconds."""
    import time

    import cv2

    cv2.setNumThreads(1)
    (renderer, light, randomise), (subjects, reps), seed = job
    t0 = time.perf_counter()
    fs = render_set(renderer, subjects, reps, light_scale=light, randomise=randomise, seed=seed)
    return job[0], fs, time.perf_counter() - t0


def render_sets(
    keys: Sequence[tuple], sizes: Mapping[bool, tuple[int, int]], seed: int, workers: int = 1
) -> tuple[dict, dict]:
    """The feature sets of ``keys`` ((renderer, light, randomise)), each of
    ``sizes[randomise]`` (subjects, reps), over ``workers`` processes: (sets, seconds each)."""
    jobs = [(k, sizes[k[2]], seed) for k in keys]
    if workers <= 1 or len(jobs) <= 1:
        done = [_render(j) for j in jobs]
    else:
        from concurrent.futures import ProcessPoolExecutor
        from multiprocessing import get_context

        # the largest first, so the pool's last job is a short one
        jobs.sort(key=lambda j: -j[1][0] * j[1][1])
        with ProcessPoolExecutor(workers, mp_context=get_context("spawn")) as ex:
            done = list(ex.map(_render, jobs))
    return {k: fs for k, fs, _ in done}, {k: round(t, 1) for k, _, t in done}


def cross_renderer(
    train_size: tuple[int, int] = TRAIN_SIZE,
    test_size: tuple[int, int] = TEST_SIZE,
    *,
    lights: Sequence[float] = LIGHTS,
    frames: Sequence[int] = FRAMES,
    seed: int = 0,
    workers: int = 1,
    sets: dict | None = None,
) -> dict:
    """Train on one renderer's domain-randomised set of ``train_size`` (subjects, reps),
    test on another's plain sets of ``test_size`` at each light (``PAIRS``), rendered
    over ``workers`` processes. ``sets``: a dict to keep the rendered feature sets in
    (reused if present)."""
    import time

    sets = {} if sets is None else sets
    keys = {(tr, 1.0, True) for tr, _ in PAIRS}
    keys |= {(te, k, False) for _, te in PAIRS for k in lights} | {("twin", 1.0, False)}
    keys |= {("phalanx", 1.0, False)}
    todo = sorted(k for k in keys if k not in sets)
    t0 = time.perf_counter()
    got, seconds = render_sets(todo, {True: train_size, False: test_size}, seed, workers)
    sets.update(got)
    render_s = time.perf_counter() - t0
    out: dict = {
        "train": {"subjects": train_size[0], "reps": train_size[1], "randomised": True},
        "test": {"subjects": test_size[0], "reps": test_size[1], "randomised": False},
        "seed": seed,
        "n_harmonics": N_HARMONICS,
        "rows": [],
    }
    t1 = time.perf_counter()
    for train_r, test_r in PAIRS:
        train = sets[(train_r, 1.0, True)]
        tests = {f"x{k:g}": sets[(test_r, k, False)] for k in lights}
        for row in transfer_rows(train, tests, frames):
            out["rows"].append({"train": train_r, "test_renderer": test_r, **row})
    # the features the two renderers disagree on most for the same gestures (x1.0)
    out["gap"] = renderer_gap(sets[("twin", 1.0, False)], sets[("phalanx", 1.0, False)], top=5)
    out["time_s"] = {
        "render_and_extract": round(render_s, 1),
        "per_set": {f"{r} x{k:g}{' randomised' if rnd else ''}": t for (r, k, rnd), t in
                    seconds.items()},
        "fit_and_test": round(time.perf_counter() - t1, 1),
        "workers": workers,
    }  # fmt: skip
    return out
