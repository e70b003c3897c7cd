"""The SVMs' C and gamma: ``grid_search`` chooses what scikit-learn's ``GridSearchCV``
chooses on the same folds (the independent reference), ties included."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.model_selection import GridSearchCV, StratifiedKFold

from plugins.gestures.model import SVC_GRID, grid_search, make_pipeline


def _data(seed: int, separation: float, n: int = 60, d: int = 12):
    rng = np.random.default_rng(seed)
    y = np.array(["tap", "drag", "pinch"])[np.arange(n) % 3]
    centres = {c: rng.normal(0.0, separation, d) for c in np.unique(y)}
    x = np.stack([centres[c] for c in y]) + rng.normal(0.0, 1.0, (n, d))
    x[:, 0] *= 50.0  # features on other scales: the fold's scaling matters
    return x, y


@pytest.mark.parametrize(
    "seed, separation",
    [(0, 0.3), (1, 0.6), (2, 1.0), (3, 5.0)],  # 5.0: every setting is right: a tie
)
def test_the_choice_is_grid_search_cv_s(seed, separation):
    x, y = _data(seed, separation)
    folds = list(StratifiedKFold(3, shuffle=True, random_state=seed).split(x, y))
    ref = GridSearchCV(make_pipeline(0), SVC_GRID, cv=folds, n_jobs=1).fit(x, y)
    assert grid_search(x, y, folds) == ref.best_params_
    if separation == 5.0:
        assert ref.cv_results_["mean_test_score"].min() == 1.0  # the tie this case is for
