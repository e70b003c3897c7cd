"""Leave-one-condition-out and light transfer on a `synth --vary` set."""

import copy

import numpy as np
import pytest

from plugins.gestures.dataset import load_dataset
from plugins.gestures.evaluate import extract
from plugins.gestures.selection import condition_report, holdout
from plugins.gestures.synth import synth


@pytest.fixture(scope="module")
def _varied_set(tmp_path_factory):
    """The varied set (synthesised and extracted once for the module: most of its tests'
    time) and its features."""
    root = tmp_path_factory.mktemp("varied") / "varied"
    gestures = ("one_finger", "two_finger", "drag", "zoom")
    synth(root, 3, 4, seed=5, workers=1, gestures=gestures, vary=True, sessions=2)
    return root, extract(root, use_cache=False)


@pytest.fixture
def varied(_varied_set):
    """The varied set's folder (read only) and a copy of its features of each test's own."""
    root, fs = _varied_set
    return root, copy.deepcopy(fs)


#: the tests of the shared varied set run in one worker (it is built once there)
VARIED = pytest.mark.xdist_group("gestures_varied_set")


@VARIED
def test_each_session_is_tested_by_a_model_trained_on_the_others(varied):
    root, fs = varied
    meta = {s.name: s.meta for s in load_dataset(root)}
    rep = condition_report(fs, meta, n_harmonics=4, n_frames=4)  # (choosing them: test_cli)
    folds = rep["leave_one_condition_out"]["folds"]
    n = len(fs.labels)
    sessions = sorted({m["session"] for m in meta.values()})
    assert sorted(f["session"] for f in folds) == sessions
    assert sessions == [f"s{k}/{j}" for k in (1, 2, 3) for j in (0, 1)]
    assert sum(f["n_test"] for f in folds) == n == 48
    pooled = sum(f["accuracy"] * f["n_test"] for f in folds) / n
    assert abs(rep["leave_one_condition_out"]["accuracy"] - pooled) < 1e-12
    assert rep["leave_one_condition_out"]["accuracy"] >= 0.6
    for f in folds:  # the fold's light is its session's
        s = f["session"]
        assert f["illumination"] == next(
            m["condition"]["illumination"] for m in meta.values() if m["session"] == s
        )
        assert (f["n_harmonics"], f["n_frames"]) == (4, 4)
    # a holdout tests only its test samples and predicts from the training part
    idx = np.arange(n)
    r = holdout(fs, idx[::2], idx[1::2], n_harmonics=2, n_frames=3)
    assert r["n_test"] == n // 2 and 0 <= r["accuracy"] <= 1 and r["n_frames"] == 3
    # a set without recorded conditions has no such report
    plain = {n: {} for n in fs.names}
    assert condition_report(fs, plain) == {"leave_one_condition_out": None, "light_transfer": None}


@VARIED
def test_each_window_is_judged_with_its_own_kind_classifier(varied):
    """A candidate's inner accuracy does not depend on which candidates were tried
    before it (each decision window has its own static-vs-dynamic classifier), and the
    inner folds keep a subject on one side."""
    from plugins.gestures.model import inner_splitter
    from plugins.gestures.selection import select_settings

    _, fs = varied
    idx = np.arange(len(fs.labels))
    a = select_settings(fs, idx, (2,), (2, 4))["scores"]
    b = select_settings(fs, idx, (2,), (4, 2))["scores"]
    assert a == b
    split = inner_splitter(fs.labels, fs.subjects, 3)
    for tr, te in split.split(idx, fs.labels, fs.subjects):
        assert not set(fs.subjects[tr]) & set(fs.subjects[te])


@VARIED
def test_a_fold_s_model_is_also_tested_under_another_light(tmp_path, varied):
    """``cross_validate(transfer=...)``: the same performances seen under x0.7 light are
    classified by each fold's model; the report has their accuracies and predictions."""
    from plugins.gestures.evaluate import cross_validate

    root, fs = varied
    dim_root = tmp_path / "dim"
    gestures = ("one_finger", "two_finger", "drag", "zoom")
    synth(dim_root, 3, 4, seed=5, workers=1, gestures=gestures, vary=True, sessions=2,
          light_scale=0.7)  # fmt: skip
    dim = extract(dim_root, use_cache=False)
    dim_meta = {s.name: s.meta for s in load_dataset(dim_root)}
    base_meta = {s.name: s.meta for s in load_dataset(root)}
    for n in fs.names:  # the same performance, at 0.7 of its session's light
        a, b = base_meta[n]["condition"]["illumination"], dim_meta[n]["condition"]["illumination"]
        assert abs(b - 0.7 * a) < 1e-3
    r = cross_validate(fs, "loso", n_harmonics=2, n_frames=4, transfer={"x0.7": dim})
    t = r["transfer"]["x0.7"]
    assert len(t["predicted"]) == len(fs.labels) and t["n_samples"] == len(fs.labels)
    acc = np.mean(np.array(t["predicted"]) == fs.labels)
    st = t["static_accuracy"] * 24 + t["dynamic_accuracy"] * 24
    assert abs(acc * 48 - st) < 1e-9
    assert acc >= 0.75
