"""``t`` on the Gestures panel says the training's size and time before it starts, as
``s`` says a synthesis's: the samples (the files block's count of the dataset), the
procedure (``2fold``: two folds, ``loso``: one per subject, then the fit on every
sample) and the time at the pace of the last training of that model (its seconds kept
in the model's metadata, ``train_s``, over its samples), or that it is said as it runs
when no training of it was timed; ``t`` again within the panel's window starts it."""

from __future__ import annotations

import time
from typing import Any

from console.plugin_api.tui import lapse, left_words


def train_pace(model: dict[str, Any]) -> float | None:
    """Seconds a sample took in the last training of the model the files block read
    (``describe_files``' model info), None when it kept no time."""
    seconds, n = model.get("train_s"), (model.get("evaluation") or {}).get("n_samples")
    if not isinstance(seconds, int | float) or not isinstance(n, int) or n <= 0:
        return None
    return float(seconds) / n


def train_question(dataset: dict[str, Any], model: dict[str, Any], cv: str, within_s: float) -> str:
    """``t again within 20 s to train: 2fold on 60 samples (2 folds, then every sample),
    about 20 s (the last training's pace, 0.33 s a sample)``."""
    n = dataset.get("samples")
    size = f"{n} samples" if isinstance(n, int) else "the dataset's samples"
    folds = "2 folds" if cv == "2fold" else "a fold per subject"
    pace = train_pace(model)
    if pace is not None and isinstance(n, int):
        about = left_words(pace * n).removesuffix(" left")
        took = f"{about} (the last training's pace, {pace:.2f} s a sample)"
    else:
        took = "its time said as it runs (no training of this model timed yet)"
    return f"t again within {within_s:.0f} s to train: {cv} on {size} ({folds}, then every sample), {took}"


def train_confirmed(panel: Any, asked: tuple, known: dict[str, Any], within_s: float) -> bool:
    """True for ``t`` again within ``within_s`` s with the same fields (``asked``: the
    dataset, model and cv); else ``t`` asks now, on the panel's work line, a question that
    lapses after ``within_s`` s, or as a field changes or another action starts (they set
    ``panel._train_asked`` to None)."""
    pending, panel._train_asked = panel._train_asked, None
    if pending is not None and pending[0] == asked and time.monotonic() <= pending[1]:
        return True
    panel._train_asked = was = (asked, time.monotonic() + within_s)
    work = panel.work
    text = train_question(known, panel.files.get("model", {}), asked[2], within_s)
    work.show(text)

    def alive() -> bool:
        return panel._train_asked == was and time.monotonic() <= was[1]

    then = "the question lapsed: t says the size and time again"
    lapse(panel, lambda: work.text, text, work.show, while_true=alive, then=then)
    return False
