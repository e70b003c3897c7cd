"""`haptable gestures eval|train|classify` on a small dataset of sketched gestures written
in the documented folder format (as someone else's recordings would be)."""

import json

import numpy as np
import pytest

from console.cli.main import main
from plugins.gestures import sketch
from plugins.gestures.dataset import write_background, write_sample

# one xdist worker runs this module: its module fixtures (a synthesised dataset, its
# feature cache) computed once
pytestmark = pytest.mark.xdist_group("gestures_cli")


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    """One feature cache for the module (train reuses what eval extracted)."""
    d = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("HAPTABLE_CACHE_DIR", str(d))
        yield d


@pytest.fixture(autouse=True)
def _module_cache(cache, monkeypatch):
    monkeypatch.setenv("HAPTABLE_CACHE_DIR", str(cache))


@pytest.fixture(scope="module")
def dataset(tmp_path_factory, cache):
    root = tmp_path_factory.mktemp("gestures") / "set"
    bg = sketch.background()
    write_background(root, bg)
    rng = np.random.default_rng(7)
    for subject in ("s1", "s2"):
        size = 0.95 if subject == "s1" else 1.08
        for g in sketch.STATIC + sketch.DYNAMIC:
            for rep in range(4):
                left = bool(rep % 2)
                poses = sketch.gesture_poses(
                    g,
                    4 if g in sketch.STATIC else 5,
                    pos_px=(rng.uniform(220, 420), rng.uniform(180, 280)),
                    theta_deg=rng.uniform(-180, 180),
                    left=left,
                    size=size * rng.uniform(0.95, 1.05),
                    speed=rng.uniform(0.8, 1.2),
                )
                frames = [sketch.draw([p], bg, rng=rng) for p in poses]
                write_sample(
                    root,
                    g,
                    f"{subject}_{rep:03d}",
                    frames,
                    subject=subject,
                    hand="left" if left else "right",
                    fps=60,
                )
    return root


def run_json(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, (json.loads(out.out) if code == 0 else out.err)


def test_eval_two_fold_and_loso(dataset, cache, capsys, one_model_setting):
    code, rep = run_json(capsys, "gestures", "eval", str(dataset), "--cv", "2fold", "--json")
    assert code == 0
    for key in ("static_accuracy", "dynamic_accuracy", "per_class_recall", "confusion"):
        assert key in rep
    assert rep["frame_ms_p50"] > 0 and rep["frame_ms_p99"] >= rep["frame_ms_p50"]
    assert rep["n_samples"] == 80
    assert rep["static_accuracy"] >= 0.8 and rep["dynamic_accuracy"] >= 0.8
    assert sum(sum(v.values()) for v in rep["confusion"].values()) == 80
    assert any((cache / "gestures").glob("*.npz"))  # features cached
    code, loso = run_json(capsys, "gestures", "eval", str(dataset), "--cv", "loso", "--json")
    assert code == 0 and loso["cv"] == "loso" and loso["subjects"] == ["s1", "s2"]


def test_train_then_classify_one_sample(dataset, capsys, tmp_path, one_model_setting):
    """Train, then classify with the saved model, from the command line and as the live
    classifier (one candidate setting: the selection is
    ``test_harmonics_and_frames_are_chosen_on_the_training_samples``'s)."""
    model = tmp_path / "m.skops"
    code, out = run_json(capsys, "gestures", "train", str(dataset), "--out", str(model), "--json")
    assert code == 0 and model.is_file() and out["samples"] == 80
    code, res = run_json(
        capsys, "gestures", "classify", str(model), str(dataset / "drag" / "s1_000"), "--json"
    )
    assert code == 0
    assert res["gesture"] == "drag" and res["kind"] == "dynamic" and res["correct"]
    code, res = run_json(
        capsys, "gestures", "classify", str(model), str(dataset / "l_shape" / "s2_001"), "--json"
    )
    assert code == 0 and res["kind"] == "static"

    # the same model as the live classifier plugin, frame by frame
    from console.core.types import Frame
    from plugins.gestures.classifier import SvmClassifier
    from plugins.gestures.dataset import read_sample
    from plugins.gestures.model import GestureModel

    s = read_sample(dataset / "drag" / "s1_000")
    clf = SvmClassifier(GestureModel.load(model), background=s.background())
    frames = [Frame(img, i, i / 60) for i, img in enumerate(s.frames())][: clf.n_frames]
    results = [clf.process(f) for f in frames]  # as the loop's vision stage does
    g = clf.classify(results, frames[-1].t_capture_s)
    assert g.name == "drag" and g.kind == "dynamic" and 0 <= g.confidence <= 1
    assert g.hand is not None and "vision" in frames[0].stamps_s
    assert SvmClassifier(None).classify(results, frames[-1].t_capture_s) is None


def test_malformed_sample_json_is_a_one_line_error(dataset, capsys, tmp_path, one_model_setting):
    import shutil

    bad = tmp_path / "bad"
    shutil.copytree(dataset, bad)
    (bad / "zoom" / "s2_003" / "sample.json").write_text('{"subject": "s2", "gesture": ')
    code, err = run_json(capsys, "gestures", "eval", str(bad), "--json", "--no-cache")
    assert code == 2
    assert "zoom/s2_003" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    code, err = run_json(capsys, "gestures", "classify", str(tmp_path / "none.skops"), str(bad))
    assert code == 2 and "gestures train" in err


@pytest.mark.slow
def test_dataset_without_any_background_still_evaluates(
    dataset, capsys, tmp_path, one_model_setting
):
    """Someone else's recordings may have no background.png: the median of the samples'
    first frames stands in for the empty table."""
    import shutil

    other = tmp_path / "nobg"
    shutil.copytree(dataset, other)
    (other / "background.png").unlink()
    code, rep = run_json(capsys, "gestures", "eval", str(other), "--json")
    assert code == 0
    assert rep["static_accuracy"] >= 0.7 and rep["dynamic_accuracy"] >= 0.7


def test_train_without_out_saves_the_profiles_model_where_the_classifier_reads_it(
    dataset, capsys, tmp_path, plugins, one_model_setting
):
    """No --out: the model goes to the profile's state directory, not beside the profile."""
    import shutil

    from console.config.profile import PROJECT_PROFILES, load_profile
    from console.files import paths
    from plugins.gestures.classifier import SvmClassifier

    shutil.copy(PROJECT_PROFILES / "sim.toml", tmp_path / "bench.toml")
    code, out = run_json(
        capsys, "-p", str(tmp_path / "bench.toml"), "gestures", "train", str(dataset), "--json"
    )
    assert code == 0
    assert out["model"] == str(paths.profile_state_dir("bench", "gestures.skops"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bench.toml"]
    clf = SvmClassifier.from_profile(load_profile(tmp_path / "bench.toml", plugins))
    assert clf.model is not None and clf.model.n_frames == out["n_frames"]


def _subset(src, dst, subject):
    """A copy of the dataset with one subject's samples (another session's recordings)."""
    import re
    import shutil

    def other(_d, names):
        return [n for n in names if re.fullmatch(r"s\d_\d+", n) and not n.startswith(subject)]

    shutil.copytree(src, dst, ignore=other)
    return dst


def test_a_model_trained_on_one_set_is_evaluated_on_another(
    dataset, capsys, tmp_path, one_model_setting
):
    one = _subset(dataset, tmp_path / "one", "s1")
    two = _subset(dataset, tmp_path / "two", "s2")
    model = tmp_path / "m.skops"
    code, out = run_json(capsys, "gestures", "train", str(one), "--out", str(model), "--json")
    assert code == 0 and out["samples"] == 40
    code, rep = run_json(capsys, "gestures", "eval", str(two), "--model", str(model), "--json")
    assert code == 0
    code, cv = run_json(capsys, "gestures", "eval", str(two), "--json")
    assert set(cv) - set(rep) == set()  # the same report as a cross-validation
    assert rep["cv"] == "model" and rep["model"] == str(model) and rep["subjects"] == ["s2"]
    assert rep["n_samples"] == 40 and rep["trained_on"] == str(one)
    assert rep["n_harmonics"] == out["n_harmonics"] and rep["n_frames"] == out["n_frames"]
    # every prediction is what `classify` says for that sample
    hits = 0
    for folder in sorted(p for p in two.glob("*/s2_*")):
        code, res = run_json(capsys, "gestures", "classify", str(model), str(folder), "--json")
        hits += bool(res["correct"])
    total = sum(v.get(g, 0) for g, v in rep["confusion"].items())
    assert hits == total and rep["static_accuracy"] >= 0.7 and rep["dynamic_accuracy"] >= 0.7
    code, err = run_json(
        capsys, "gestures", "eval", str(two), "--model", str(tmp_path / "none.skops")
    )
    assert code == 2 and "gestures train" in err and len(err.strip().splitlines()) == 1


def test_harmonics_and_frames_are_chosen_on_the_training_samples(
    dataset, capsys, tmp_path, monkeypatch
):
    from plugins.gestures.evaluate import extract
    from plugins.gestures.model import GestureModel
    from plugins.gestures.selection import select_settings

    model = tmp_path / "m.skops"
    code, out = run_json(capsys, "gestures", "train", str(dataset), "--out", str(model), "--json")
    assert code == 0
    sel = out["selection"]
    assert sel["searched"] == {"n_harmonics": [2, 4, 6, 8], "n_frames": [2, 3, 4]}
    assert out["n_harmonics"] in (2, 4, 6, 8) and out["n_frames"] in (2, 3, 4)
    best = sel["inner_cv_accuracy"][f"h{out['n_harmonics']}_f{out['n_frames']}"]
    assert best == max(sel["inner_cv_accuracy"].values()) and len(sel["inner_cv_accuracy"]) == 12
    saved = GestureModel.load(model)
    assert saved.meta["selection"] == sel and saved.n_frames == out["n_frames"]
    # the SVMs' C and gamma, chosen by cross-validation, are in the model and the output
    for part in ("static", "dynamic", "kind"):
        assert sel["svm"][part]["C"] in (1.0, 10.0, 100.0)
        assert sel["svm"][part]["gamma"] in ("scale", 0.003, 0.03)
    assert sel["svm"] == saved.svm_settings()
    # given values are kept, nothing searched
    code, fixed = run_json(
        capsys, "gestures", "train", str(dataset), "--out", str(model), "--harmonics", "4",
        "--frames", "3", "--json",
    )  # fmt: skip
    assert (fixed["n_harmonics"], fixed["n_frames"]) == (4, 3)
    assert fixed["selection"]["inner_cv_accuracy"] is None
    # nested: each outer fold chooses on its own training part, reported in the eval JSON
    # (among fewer candidates: the search itself is tested above)
    from plugins.gestures import selection

    monkeypatch.setattr(selection, "HARMONICS_CANDIDATES", (2, 6))
    monkeypatch.setattr(selection, "FRAMES_CANDIDATES", (2, 4))
    code, rep = run_json(capsys, "gestures", "eval", str(dataset), "--cv", "loso", "--json")
    assert [f["subject"] for f in rep["folds"]] == ["s1", "s2"]
    assert len(rep["selection"]["chosen_per_fold"]) == 2
    assert all(f["n_frames"] in (2, 4) and len(f["selection"]) == 4 for f in rep["folds"])
    assert all(f["svm"]["static"]["C"] in (1.0, 10.0, 100.0) for f in rep["folds"])
    # the choice sees the training samples only: other samples' labels do not matter
    fs = extract(dataset)
    tr = np.flatnonzero(fs.subjects == "s1")
    a = select_settings(fs, tr, (2, 6), (2, 4))
    fs.labels[fs.subjects == "s2"] = "tap"
    assert select_settings(fs, tr, (2, 6), (2, 4)) == a
