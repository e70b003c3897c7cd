"""A dataset's features as arrays (``FeatureSet``, one row per sample, for each decision
window) and the columns a classifier with given settings takes from them."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from console.plugin_api import UserError

from . import features as F
from .features import N_HARMONICS_MAX


@dataclass
class FeatureSet:
    """Per-sample features of a dataset."""

    names: list[str]
    labels: np.ndarray
    subjects: np.ndarray
    # per decision window k (the first k frames): static features (mean over the
    # window), motion features (static vs dynamic), dynamic features, motion score
    static: dict[int, np.ndarray]
    kind: dict[int, np.ndarray]
    dynamic: dict[int, np.ndarray]
    score: dict[int, np.ndarray]
    frame_s: np.ndarray  # pipeline wall time of every frame processed
    meta: dict = field(default_factory=dict)
    frame_cpu_s: np.ndarray = field(default_factory=lambda: np.zeros(0))  # thread CPU time

    def subset(self, idx: np.ndarray) -> FeatureSet:
        return FeatureSet(
            [self.names[i] for i in idx],
            self.labels[idx],
            self.subjects[idx],
            {k: v[idx] for k, v in self.static.items()},
            {k: v[idx] for k, v in self.kind.items()},
            {k: v[idx] for k, v in self.dynamic.items()},
            {k: v[idx] for k, v in self.score.items()},
            self.frame_s,
            self.meta,
            self.frame_cpu_s,
        )


def columns(fs: FeatureSet, n_harmonics: int, n_frames: int):
    """(static X, dynamic X, kind X, motion score) with ``n_harmonics``, decided from the
    first ``n_frames`` frames."""
    if n_frames not in fs.dynamic:
        raise UserError(
            f"--frames {n_frames}: features exist for {sorted(fs.dynamic)} frames (no longer "
            "than the dataset's shortest sample); pick one of them"
        )
    nmax = int(fs.meta.get("n_harmonics_max", N_HARMONICS_MAX))
    if not (n_harmonics == 0 or 2 <= n_harmonics <= nmax):
        raise UserError(f"--harmonics {n_harmonics}: use 0 (no descriptors) or 2 to {nmax}")
    xs = F.select_static(fs.static[n_frames], n_harmonics, nmax)
    xd = F.select_dynamic(fs.dynamic[n_frames], n_harmonics, nmax)
    return xs, xd, F.select_kind(fs.kind[n_frames]), fs.score[n_frames]
