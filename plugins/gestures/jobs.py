"""Long gesture jobs as plain functions with progress and cancellation (the console's
Gestures panel runs them in thread workers; the CLI uses the same code):

- ``synth_atomic``: a twin dataset written beside ``out`` and renamed into place, so a
  cancelled or failed run leaves no half-written dataset (and the previous one intact);
- ``train_and_evaluate``: features, cross-validation (accuracy per fold), the model on
  all samples with the evaluation in its metadata, saved by write-then-rename;
- ``describe_files``: what the dataset and model files hold (for the panel).
"""

from __future__ import annotations

import json
import os
import shutil
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from console.plugin_api import AT_CONSOLE, UserError, worded

from .dataset import load_dataset
from .progress import CancelCheck, Progress, part, step
from .synth import synth

SYNTH_MARK = "synth.json"  # a folder with this file was made by the twin (replaceable)


def dataset_refusal(path: Path) -> str:
    """Why ``path`` cannot be a dataset folder (something else is there), or "": the
    one account synthesis, training and the panel's files block give."""
    if path.exists() and not path.is_dir():
        return f"{path}: exists and is not a folder; choose another dataset folder"
    return ""


def model_refusal(path: Path) -> str:
    """Why ``path`` cannot be a model file (a folder is there), or ""."""
    if path.is_dir():
        return f"{path}: is a folder; give a model file such as gestures.skops"
    return ""


def _tree_bytes(root: Path) -> int:
    return sum(p.stat().st_size for p in root.rglob("*") if p.is_file())


def synth_atomic(
    out: str | Path,
    subjects: int,
    reps: int,
    *,
    replace: bool = False,
    progress: Progress | None = None,
    cancelled: CancelCheck | None = None,
    make: Callable[..., dict[str, Any]] = synth,
    **synth_kw: Any,
) -> dict[str, Any]:
    """``make`` (``synth.synth``, or another renderer's writer of the same signature)
    into a hidden sibling folder, renamed to ``out`` when complete.

    An existing non-empty ``out`` is an error, unless ``replace`` and it is a synthesized
    dataset (has ``synth.json``): then it is swapped for the new one at the end.
    ``Cancelled`` (or any error) removes the partial folder and leaves ``out`` as it was.
    """
    out = Path(out).expanduser()
    if subjects < 1 or reps < 1:
        raise UserError(f"subjects {subjects}, reps {reps}: both must be at least 1")
    if dataset_refusal(out):
        raise UserError(dataset_refusal(out))
    old_set = out.is_dir() and any(out.iterdir())
    if old_set and not (replace and (out / SYNTH_MARK).is_file()):
        why = "is not a synthesized dataset (no synth.json)" if replace else "is not empty"
        raise UserError(f"{out}: folder {why}; choose a new dataset folder")
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.parent / f".{out.name}.partial-{os.getpid()}"
    shutil.rmtree(tmp, ignore_errors=True)
    try:
        info = make(tmp, subjects, reps, progress=progress, cancelled=cancelled, **synth_kw)
        step(None, cancelled, 1.0, "renaming")
        info["out"] = str(out)
        (tmp / SYNTH_MARK).write_text(json.dumps(info, indent=1) + "\n")
        if out.is_dir() and not old_set:
            out.rmdir()
        if old_set:
            old = out.parent / f".{out.name}.old-{os.getpid()}"
            os.replace(out, old)
            os.replace(tmp, out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    info["bytes"] = _tree_bytes(out)
    return info


def synth_target(out: str | Path) -> dict[str, Any]:
    """What ``synth_atomic`` into ``out`` does to what is there: ``replace`` False for a
    missing or empty folder (a new dataset); True for a synthesized one, which it swaps
    for the new one (never adds to it), with that one's ``samples``, ``subjects`` and
    ``reps`` (None when unreadable). Any other folder, or a file, is a ``UserError``."""
    out = Path(out).expanduser()
    if dataset_refusal(out):
        raise UserError(dataset_refusal(out))
    if not out.is_dir() or not any(out.iterdir()):
        return {"replace": False}
    if not (out / SYNTH_MARK).is_file():
        raise UserError(
            f"{out}: folder is not a synthesized dataset (no {SYNTH_MARK}); "
            "choose another dataset folder"
        )
    info = describe_files(out, None)["dataset"]
    subjects = info.get("subjects")
    return {
        "replace": True,
        "samples": info.get("samples"),
        "subjects": len(subjects) if subjects else None,
        "reps": info.get("reps"),
    }


def train_and_evaluate(
    dataset: str | Path,
    model_out: str | Path,
    *,
    profile: Any = None,
    cv: str = "2fold",
    n_harmonics: int | None = None,
    n_frames: int | None = None,
    seed: int = 0,
    use_cache: bool = True,
    progress: Progress | None = None,
    cancelled: CancelCheck | None = None,
) -> dict[str, Any]:
    """``evaluate.evaluation`` (``haptable gestures eval``'s procedure and defaults:
    ``2fold`` or ``loso``, harmonics and frames chosen inside each training part unless
    given) then train on every sample as ``haptable gestures train`` does and save the
    model to ``model_out``; the evaluation (its procedure, accuracy per fold) goes into
    the model's metadata. Progress: features and folds 0-90 %, final fit and save.
    Nothing is written when cancelled."""
    from . import evaluate as ev  # lazy: OpenCV, scikit-learn (dataset_commands loads jobs)

    t0 = time.monotonic()
    dataset, model_out = Path(dataset).expanduser(), Path(model_out).expanduser()
    if model_refusal(model_out):
        raise UserError(model_refusal(model_out))
    fs, rep = ev.evaluation(  # the same procedure as `haptable gestures eval`
        dataset,
        profile,
        cv=cv,
        n_harmonics=n_harmonics,
        n_frames=n_frames,
        seed=seed,
        use_cache=use_cache,
        progress=part(progress, 0.0, 0.9),
        cancelled=cancelled,
    )
    keys = ("cv", "procedure", "n_samples", "subjects", "static_accuracy", "dynamic_accuracy")
    evaluation = {k: rep[k] for k in (*keys, "folds")}
    step(progress, cancelled, 0.9, "training on every sample")
    model = ev.train(
        fs,
        n_harmonics=n_harmonics,
        n_frames=n_frames,
        max_frames=ev.max_frames(profile),
        seed=seed,
        meta={"evaluation": evaluation, "dataset": str(dataset)},
        cancelled=cancelled,
    )
    step(progress, cancelled, 0.97, "saving the model")
    model.meta["train_s"] = round(time.monotonic() - t0, 1)  # the next t says its time
    model_out.parent.mkdir(parents=True, exist_ok=True)
    path = model.save(model_out)
    step(progress, None, 1.0, "saved")
    return {"model": str(path), "bytes": path.stat().st_size, **evaluation}


def describe_files(dataset: str | Path | None, model: str | Path | None) -> dict[str, Any]:
    """Where the dataset and model are, their size, the dataset's subjects and
    repetitions and the model's evaluation (from its metadata). A missing or unreadable
    file is described (worded for the panel), never raised."""
    out: dict[str, Any] = {}
    if dataset is not None:
        d = Path(dataset).expanduser()
        info: dict[str, Any] = {"path": str(d), "exists": d.is_dir()}
        if dataset_refusal(d):  # said as s and t say it, never "none yet"
            info["error"] = dataset_refusal(d)
        elif d.is_dir():
            try:
                samples = load_dataset(d)
                reps: dict[tuple[str, str], int] = {}
                for smp in samples:
                    reps[(smp.subject, smp.gesture)] = reps.get((smp.subject, smp.gesture), 0) + 1
                info.update(
                    samples=len(samples),
                    subjects=sorted({smp.subject for smp in samples}),
                    gestures=len({smp.gesture for smp in samples}),
                    reps=max(reps.values()),
                    bytes=_tree_bytes(d),
                )
            except UserError as exc:
                info["error"] = worded(exc, AT_CONSOLE)
        out["dataset"] = info
    if model is not None:
        m = Path(model).expanduser()
        info = {"path": str(m), "exists": m.is_file()}
        if model_refusal(m):
            info["error"] = model_refusal(m)
        elif m.is_file():
            info["bytes"] = m.stat().st_size
            try:
                from .model import read_settings  # lazy: OpenCV (the sketches)

                meta = read_settings(m).get("meta", {})
                info["n_samples"] = meta.get("n_samples")
                info["evaluation"] = meta.get("evaluation")
                info["trained_on"] = meta.get("trained_on")
                info["train_s"] = meta.get("train_s")
            except UserError as exc:
                info["error"] = worded(exc, AT_CONSOLE)
        out["model"] = info
    return out
