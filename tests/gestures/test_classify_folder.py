"""`haptable gestures classify MODEL FOLDER` given a gesture folder (or a whole dataset)
instead of one sample: it says so and classifies every sample in it (issue 27: it asked
for a sample.json)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from console.cli.main import main
from plugins.gestures import sketch
from plugins.gestures.dataset import write_background, write_sample


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    root = tmp_path_factory.mktemp("gs") / "set"
    bg = sketch.background()
    write_background(root, bg)
    rng = np.random.default_rng(5)
    for subject in ("s1", "s2"):
        for g in sketch.STATIC + sketch.DYNAMIC:
            for rep in range(2):
                poses = sketch.gesture_poses(
                    g, 4 if g in sketch.STATIC else 5,
                    pos_px=(rng.uniform(220, 420), rng.uniform(180, 280)),
                    theta_deg=rng.uniform(-180, 180), left=False,
                )  # fmt: skip
                frames = [sketch.draw([p], bg, rng=rng) for p in poses]
                write_sample(
                    root, g, f"{subject}_{rep:03d}", frames, subject=subject, hand="right", fps=60
                )
    model = root.parent / "m.skops"
    args = ["gestures", "train", str(root), "--out", str(model), "--harmonics", "2"]
    assert main([*args, "--frames", "4", "--json"]) == 0
    return root, model


def test_a_gesture_folder_classifies_each_sample(trained, capsys):
    root, model = trained
    capsys.readouterr()
    assert main(["gestures", "classify", str(model), str(root / "drag"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["folder"] == str(root / "drag") and out["holds"] == "gesture folder"
    assert out["samples"] == 4 == len(out["results"])
    assert {r["sample"] for r in out["results"]} == {
        "drag/s1_000", "drag/s1_001", "drag/s2_000", "drag/s2_001"
    }  # fmt: skip
    assert all(r["label"] == "drag" for r in out["results"])
    assert out["correct"] == sum(r["gesture"] == "drag" for r in out["results"])

    # in text: what the folder is, then a line per sample
    assert main(["gestures", "classify", str(model), str(root / "drag")]) == 0
    text = capsys.readouterr().out
    assert "a gesture folder: 4 samples classified" in text and "drag/s1_000" in text

    # a whole dataset: every sample of every gesture
    assert main(["gestures", "classify", str(model), str(root), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["holds"] == "dataset" and out["samples"] == 40


def test_a_folder_with_no_samples_says_what_to_give(trained, tmp_path, capsys):
    _, model = trained
    (tmp_path / "empty").mkdir()
    assert main(["gestures", "classify", str(model), str(tmp_path / "empty")]) == 2
    err = capsys.readouterr().err
    assert "no sample.json and no sample folders" in err and "DATASET/drag/s1_000" in err
