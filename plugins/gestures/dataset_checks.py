"""Checks of a dataset's features before a model is trained or judged on them.

A dataset whose frames show no hand the vision pipeline can segment (the lens cap on:
all black; the lamp blinding the camera: all white; a noisy sensor) gives every sample
the "no hand" feature vector: a model trained on it learns nothing, an evaluation on it
measures nothing. Such a gesture is refused in one line naming the dataset, the gesture
and a sample, before any fit; a few samples without a hand among good ones pass (a
gesture started late, a blink of the light).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import UserError

from . import features as F


def hand_seen(fs: Any) -> np.ndarray:
    """Per sample: did any frame of its longest decision window show a hand (the static
    features' hand flag, ``features.record_static``: 1 with a hand, -1 without)."""
    k = max(fs.static)
    nmax = int(fs.meta.get("n_harmonics_max", 16))
    flag = F.desc_size(nmax) + F.N_GRID + 1
    return np.asarray(fs.static[k])[:, flag] > 0


def require_hands(fs: Any, root: str | Path) -> None:
    """``UserError`` when no sample of some gesture shows a hand (or no sample at all)."""
    seen = hand_seen(fs)
    if seen.all():
        return
    labels = np.asarray(fs.labels).astype(str)
    fix = (
        "its frames show no hand the vision can find (all black, all white or noise?): "
        "check the camera's exposure and the dataset's background.png, or record it again"
    )
    if not seen.any():
        raise UserError(
            f"{root}: no hand in any frame of its {len(seen)} samples (e.g. {fs.names[0]}); " + fix
        )
    for g in sorted(set(labels)):
        mine = labels == g
        if not seen[mine].any():
            first = fs.names[int(np.flatnonzero(mine)[0])]
            raise UserError(
                f"{root}: gesture {g}: no hand in any frame of its {int(mine.sum())} samples "
                f"(e.g. {first}); " + fix
            )
