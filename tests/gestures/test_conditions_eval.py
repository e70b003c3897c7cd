"""Leave-one-condition-out and light transfer on a `synth --vary` set."""

import numpy as np

from plugins.gestures.dataset import load_dataset
from plugins.gestures.evaluate import extract
from plugins.gestures.selection import condition_report, holdout
from plugins.gestures.synth import synth


def test_each_session_is_tested_by_a_model_trained_on_the_others(tmp_path):
    root = tmp_path / "varied"
    gestures = ("one_finger", "open_hand", "drag", "zoom")
    synth(root, 2, 4, seed=2, workers=1, gestures=gestures, vary=True, sessions=2)
    fs = extract(root, use_cache=False)
    meta = {s.name: s.meta for s in load_dataset(root)}
    rep = condition_report(fs, meta, n_harmonics=4, n_frames=4)  # (choosing them: test_cli)
    folds = rep["leave_one_condition_out"]["folds"]
    assert sorted(f["session"] for f in folds) == ["s1/0", "s1/1", "s2/0", "s2/1"]
    assert sum(f["n_test"] for f in folds) == len(fs.labels) == 32
    pooled = sum(f["accuracy"] * f["n_test"] for f in folds) / 32
    assert abs(rep["leave_one_condition_out"]["accuracy"] - pooled) < 1e-12
    assert rep["leave_one_condition_out"]["accuracy"] >= 0.6
    for f in folds:  # the fold's light is its session's
        s = f["session"]
        assert f["illumination"] == next(
            m["condition"]["illumination"] for m in meta.values() if m["session"] == s
        )
        assert (f["n_harmonics"], f["n_frames"]) == (4, 4)
    # a holdout tests only its test samples and predicts from the training part
    idx = np.arange(32)
    r = holdout(fs, idx[::2], idx[1::2], n_harmonics=2, n_frames=3)
    assert r["n_test"] == 16 and 0 <= r["accuracy"] <= 1 and r["n_frames"] == 3
    # a set without recorded conditions has no such report
    plain = {n: {} for n in fs.names}
    assert condition_report(fs, plain) == {"leave_one_condition_out": None, "light_transfer": None}
