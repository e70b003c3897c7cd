"""Gesture model: kind threshold, nested search, skops persistence with an allow-list."""

import numpy as np
import pytest
import skops.io as sio

from console.core.errors import UserError
from plugins.gestures.model import GestureModel, fit_threshold
from plugins.gestures.sketch import DYNAMIC, STATIC


def toy(n_per=8, seed=0):
    rng = np.random.default_rng(seed)
    labels, xs, xd, xk, sc = [], [], [], [], []
    for i, g in enumerate(STATIC + DYNAMIC):
        for _ in range(n_per):
            labels.append(g)
            xs.append(rng.normal(i, 0.3, 6))
            xd.append(rng.normal(-i, 0.3, 8))
            xk.append(rng.normal(0.0 if g in STATIC else 1.0, 0.2, 3))
            sc.append(rng.uniform(0.0, 0.1) if g in STATIC else rng.uniform(0.3, 1.0))
    return np.array(xs), np.array(xd), np.array(xk), np.array(sc), np.array(labels)


def test_threshold_separates_kinds():
    score = np.array([0.01, 0.02, 0.05, 0.4, 0.5, 0.9])
    dyn = np.array([False, False, False, True, True, True])
    t = fit_threshold(score, dyn)
    assert 0.05 < t < 0.4


def test_fit_predict_save_load_round_trip(tmp_path):
    xs, xd, xk, sc, y = toy()
    m = GestureModel.fit(xs, xd, xk, sc, y, n_harmonics=8, n_frames=4)
    pred = m.predict(xs, xd, xk)
    assert np.mean(pred == y) > 0.95
    p = m.save(tmp_path / "m.skops")
    back = GestureModel.load(p, check_features=False)  # toy features, not the pipeline's
    assert back.n_harmonics == 8 and back.n_frames == 4
    assert back.motion_threshold == pytest.approx(m.motion_threshold)
    np.testing.assert_array_equal(back.predict(xs, xd, xk), pred)


def test_untrusted_types_are_refused(tmp_path):
    from sklearn.linear_model import LogisticRegression

    xs, xd, xk, sc, y = toy(4)
    bad = {
        "format": "haptable-gestures/1",
        "static_svm": LogisticRegression(max_iter=2000).fit(xs, y),
    }
    sio.dump(bad, tmp_path / "bad.skops")
    with pytest.raises(UserError, match="allow-list.*LogisticRegression"):
        GestureModel.load(tmp_path / "bad.skops")
    (tmp_path / "junk.skops").write_bytes(b"not a zip")
    with pytest.raises(UserError, match="junk.skops"):
        GestureModel.load(tmp_path / "junk.skops")
    with pytest.raises(UserError, match="gestures train"):
        GestureModel.load(tmp_path / "missing.skops")
