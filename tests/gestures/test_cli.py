"""`haptable gestures eval|train|classify` on a small dataset of sketched gestures written
in the documented folder format (as someone else's recordings would be)."""

import json

import numpy as np
import pytest

from console.cli import main
from plugins.gestures import sketch
from plugins.gestures.dataset import write_background, write_sample


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
                    3 if g in sketch.STATIC else 5,
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


def test_eval_two_fold_and_loso(dataset, cache, capsys):
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


def test_train_then_classify_one_sample(dataset, capsys, tmp_path):
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
    from console.types import Frame
    from plugins.gestures.classifier import SvmClassifier
    from plugins.gestures.dataset import read_sample
    from plugins.gestures.model import GestureModel

    s = read_sample(dataset / "drag" / "s1_000")
    clf = SvmClassifier(GestureModel.load(model), background=s.background())
    frames = [Frame(img, i, i / 60) for i, img in enumerate(s.frames())]
    g = clf.classify(frames)
    assert g.name == "drag" and g.kind == "dynamic" and 0 <= g.confidence <= 1
    assert g.hand is not None and "vision" in frames[0].stamps_s
    assert SvmClassifier(None).classify(frames) is None


def test_malformed_sample_json_is_a_one_line_error(dataset, capsys, tmp_path):
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
def test_dataset_without_any_background_still_evaluates(dataset, capsys, tmp_path):
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
    dataset, capsys, tmp_path, plugins
):
    """No --out: the model goes to the profile's state directory, not beside the profile."""
    import shutil

    from console import paths
    from console.profile import PROJECT_PROFILES, load_profile
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
