"""Long gesture jobs with progress and cancellation: a cancelled synthesis or training
leaves no half-written dataset or model (and the previous dataset intact); training
reports accuracy per fold, consistent with the overall accuracy, and keeps it in the
model's metadata."""

from __future__ import annotations

import json

import numpy as np
import pytest

from console.core.errors import UserError
from plugins.gestures import sketch
from plugins.gestures.dataset import write_background, write_sample
from plugins.gestures.jobs import describe_files, synth_atomic, train_and_evaluate
from plugins.gestures.model import GestureModel, read_settings
from plugins.gestures.progress import Cancelled

FEW = ("one_finger", "open_hand", "drag")


@pytest.fixture(scope="module")
def sketched(tmp_path_factory):
    """2 subjects x 10 gestures x 2 reps drawn with the fast sketch renderer."""
    root = tmp_path_factory.mktemp("jobs") / "set"
    bg = sketch.background()
    write_background(root, bg)
    rng = np.random.default_rng(3)
    for si, subject in enumerate(("s1", "s2")):
        for g in sketch.STATIC + sketch.DYNAMIC:
            for rep in range(2):
                poses = sketch.gesture_poses(
                    g,
                    4 if g in sketch.STATIC else 5,
                    pos_px=(rng.uniform(240, 400), rng.uniform(200, 260)),
                    theta_deg=rng.uniform(-60, 60),
                    size=(0.95, 1.05)[si],
                )
                frames = [sketch.draw([p], bg, rng=rng) for p in poses]
                write_sample(
                    root, g, f"{subject}_{rep:03d}", frames, subject=subject, hand="right", fps=60
                )
    return root


@pytest.fixture(scope="module")
def module_cache(tmp_path_factory):
    """One feature cache for the module: the sketched set's features are extracted once."""
    return tmp_path_factory.mktemp("cache")


@pytest.fixture(autouse=True)
def _module_cache(module_cache, monkeypatch):
    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(module_cache))


def test_synth_reports_progress_and_a_cancel_keeps_the_previous_set(tmp_path):
    out = tmp_path / "data" / "twin"
    seen: list[tuple[float, str]] = []
    info = synth_atomic(
        out, 1, 2, workers=1, gestures=FEW, progress=lambda f, m: seen.append((f, m))
    )
    assert info["samples"] == 6 and info["out"] == str(out)
    fracs = [f for f, _ in seen]
    assert fracs == sorted(fracs) and fracs[-1] == 1.0 and len(fracs) >= 6
    assert json.loads((out / "synth.json").read_text())["out"] == str(out)
    before = sorted(p.relative_to(out) for p in out.rglob("*"))

    calls = []

    def cancel_after_two() -> bool:
        calls.append(1)
        return len(calls) > 2

    with pytest.raises(Cancelled):
        synth_atomic(out, 2, 3, replace=True, workers=1, gestures=FEW, cancelled=cancel_after_two)
    assert sorted(p.relative_to(out) for p in out.rglob("*")) == before
    assert [p.name for p in out.parent.iterdir()] == ["twin"]  # no partial folder left

    again = synth_atomic(out, 2, 1, replace=True, workers=1, gestures=FEW)
    assert again["samples"] == 6 and describe_files(out, None)["dataset"]["subjects"] == [
        "s1",
        "s2",
    ]


def test_synth_refuses_to_replace_a_folder_it_did_not_make(tmp_path):
    mine = tmp_path / "recordings"
    mine.mkdir()
    (mine / "notes.txt").write_text("real data")
    with pytest.raises(UserError, match="not a synthesized dataset"):
        synth_atomic(mine, 1, 1, replace=True, workers=1, gestures=FEW)
    with pytest.raises(UserError, match="not empty"):
        synth_atomic(mine, 1, 1, workers=1, gestures=FEW)
    with pytest.raises(UserError, match="at least 1"):
        synth_atomic(tmp_path / "new", 1, 0, workers=1)
    assert (mine / "notes.txt").read_text() == "real data"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["recordings"]


def test_training_cancelled_at_a_fold_writes_no_model(sketched, tmp_path, one_model_setting):
    model = tmp_path / "m.skops"
    msgs: list[str] = []

    def stop_at_fold_2() -> bool:
        return any(m.startswith("fold 2") for m in msgs)

    with pytest.raises(Cancelled):
        train_and_evaluate(
            sketched, model, progress=lambda f, m: msgs.append(m), cancelled=stop_at_fold_2
        )
    assert any(m.startswith("fold 1") for m in msgs)
    assert not model.exists()
    assert [p.name for p in tmp_path.iterdir()] == []


@pytest.mark.parametrize("cv", ["2fold", "loso"])
def test_training_reports_accuracy_per_fold_in_the_model(sketched, tmp_path, cv, one_model_setting):
    model = tmp_path / "m.skops"
    seen: list[float] = []
    res = train_and_evaluate(sketched, model, cv=cv, progress=lambda f, m: seen.append(f))
    assert seen == sorted(seen) and seen[-1] == 1.0
    folds = res["folds"]
    assert len(folds) == 2 and sum(f["n_test"] for f in folds) == res["n_samples"] == 40
    # the folds' accuracies weighted by their test sizes give the overall accuracy
    overall = sum(f["accuracy"] * f["n_test"] for f in folds) / 40
    assert overall == pytest.approx((res["static_accuracy"] + res["dynamic_accuracy"]) / 2)
    if cv == "loso":
        assert sorted(f["subject"] for f in folds) == ["s1", "s2"]
    meta = read_settings(model)["meta"]
    assert meta["evaluation"]["folds"] == folds and meta["n_samples"] == 40
    assert GestureModel.load(model).meta["evaluation"]["cv"] == cv  # allow-listed load
    files = describe_files(sketched, model)
    assert files["dataset"]["reps"] == 2 and files["dataset"]["samples"] == 40
    assert files["model"]["evaluation"]["static_accuracy"] == res["static_accuracy"]
    assert [p.name for p in tmp_path.iterdir()] == ["m.skops"]


def test_describe_files_says_what_is_missing_or_unreadable(tmp_path):
    bad = tmp_path / "m.skops"
    bad.write_text("not a zip")
    info = describe_files(tmp_path / "none", bad)
    assert info["dataset"]["exists"] is False
    assert "not a readable gesture model" in info["model"]["error"]
