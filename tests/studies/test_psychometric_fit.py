"""The psychometric fit (plugins/studies/psychometric.py) against independent fits of the
same data: a brute-force likelihood on a fine grid written here in numpy, and psignifit 4
(MAP with flat priors = the maximum likelihood); its bootstrap intervals cover the truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from console.core.errors import UserError
from plugins.studies import psychometric as pm
from plugins.studies.adaptive_pf import core, p_correct


def _p_ref(x, family, t, s, lam, g):
    """The model written out again, independently of adaptive_pf."""
    u = s * (x - t) / 20.0
    f = 1 - np.exp(-(10.0**u)) if family == "weibull" else 1 / (1 + 10.0 ** (-u))
    return g + (1 - g - lam) * f


def _grid_ml(x, n, k, family, g, lam_fixed=None):
    """Brute force: the log-likelihood on a 3-D grid, refined three times around its max."""
    t_lo, t_hi, s_lo, s_hi, l_lo, l_hi = -40.0, 0.0, 0.2, 20.0, 0.0, 0.1
    for _ in range(4):
        T = np.linspace(t_lo, t_hi, 61)[:, None, None, None]
        S = np.geomspace(s_lo, s_hi, 61)[None, :, None, None]
        L = (np.array([lam_fixed]) if lam_fixed is not None else np.linspace(l_lo, l_hi, 41))[
            None, None, :, None
        ]
        p = np.clip(_p_ref(x, family, T, S, L, g), 1e-12, 1 - 1e-12)
        ll = (k * np.log(p) + (n - k) * np.log(1 - p)).sum(-1)
        i, j, m = np.unravel_index(np.argmax(ll), ll.shape)
        t, s, lam = T[i, 0, 0, 0], S[0, j, 0, 0], L[0, 0, m, 0]
        dt, ds, dl = (t_hi - t_lo) / 10, (s_hi / s_lo) ** 0.1, (l_hi - l_lo) / 10
        t_lo, t_hi, s_lo, s_hi = t - dt, t + dt, s / ds, s * ds
        l_lo, l_hi = max(0.0, lam - dl), min(0.1, lam + dl)
    return t, s, lam


def _data(family, t, s, lam, g, seed, n_per=80):
    x = np.arange(-32.0, -3.0, 2.0)
    n = np.full(x.size, n_per)
    k = np.random.default_rng(seed).binomial(n, _p_ref(x, family, t, s, lam, g))
    return x, n, k


@pytest.mark.parametrize(
    ("family", "task", "g", "lapse"),
    [("weibull", "2afc", 0.5, None), ("logistic", "3afc", 1 / 3, 0.02)],
)
def test_fit_agrees_with_a_brute_force_grid_likelihood(family, task, g, lapse):
    x, n, k = _data(family, -18.0, 4.0, 0.04, g, seed=11)
    f = pm.fit(x, n, k, family=family, task=task, lapse=lapse, n_boot=0)
    t, s, lam = _grid_ml(x, n, k, family, g, lapse)
    assert f.threshold_db == pytest.approx(t, rel=0.01)
    assert f.slope == pytest.approx(s, rel=0.01)
    assert abs(f.lapse - lam) <= 0.001  # 1 % of the lapse's range 0..0.1
    assert f.guess == g
    # and both near the truth that made the data
    assert abs(f.threshold_db + 18.0) < 1.5


def test_fit_agrees_with_psignifit():
    psignifit = pytest.importorskip("psignifit")
    x, n, k = _data("logistic", -15.0, 4.0, 0.04, 0.5, seed=5)
    f = pm.fit(x, n, k, family="logistic", task="2afc", n_boot=0)

    def flat(v):
        return np.ones_like(np.asarray(v, float))

    def lapse_prior(v):  # flat on our lapse's range 0..0.1
        v = np.asarray(v, float)
        return ((v >= 0) & (v <= 0.1)).astype(float)

    r = psignifit.psignifit(
        np.c_[x, k, n],
        sigmoid="logistic",
        experiment_type="2AFC",
        fixed_parameters={"eta": 0.0},
        bounds={"lambda": (0.0, 0.1)},
        estimate_type="MAP",
        priors={"threshold": flat, "width": flat, "lambda": lapse_prior},
    )
    pe = r.parameter_estimate
    # psignifit's width: the 5 %..95 % span of F; ours: F = 1 / (1 + 10^(-slope z / 20))
    slope = 40 * math.log10(19) / pe["width"]
    assert f.threshold_db == pytest.approx(pe["threshold"], rel=0.01)
    assert f.slope == pytest.approx(slope, rel=0.01)
    assert abs(f.lapse - pe["lambda"]) <= 0.001
    assert 0.005 < f.lapse < 0.095  # an inside optimum, not a bound


def test_bootstrap_interval_covers_the_truth_and_is_narrow():
    rows = []
    rng = np.random.default_rng(2)
    levels = rng.uniform(-30, -6, 400)  # an adaptive run's scattered levels
    for lv in np.round(levels):
        p = _p_ref(lv, "weibull", -20.0, 3.0, 0.02, 0.5)
        rows.append({"level_db": float(lv), "correct": bool(rng.random() < p)})
    f = pm.fit_trials(rows, family="weibull", task="2afc", n_boot=30, seed=1)
    lo, hi = f.ci["threshold_db"]
    assert lo <= -20.0 <= hi and hi - lo < 4.0
    lo, hi = f.ci["slope"]
    assert lo <= 3.0 <= hi
    assert "bootstrap" in f.ci_method and "seed 1" in f.ci_method
    # the same seed, the same intervals
    assert pm.fit_trials(rows, n_boot=30, seed=1).ci == f.ci


def test_gradient_matches_the_model():
    z = np.linspace(-20, 20, 8)
    for family in ("weibull", "logistic"):
        f, d = pm._core_and_slope(z, 2.0, family)
        assert np.allclose(f, core(z, family, 0.0, 2.0))
        h = 1e-6
        fd = (core(z, family, 0.0, 2.0 + h) - core(z, family, 0.0, 2.0 - h)) / (2 * h) / z
        assert np.allclose(d, fd, rtol=1e-4, atol=1e-9)
    assert np.allclose(p_correct(-18.0, "logistic", -18.0, 1.0, 0.5, 0.0), 0.75)


@pytest.mark.parametrize(
    ("args", "kw", "match"),
    [
        (([1, 2], [10], [5]), {}, "2 levels, 1 trial counts"),
        (([1, 2], [10, 10], [5, 11]), {}, "0 <= correct <= trials"),
        (([1, 1], [10, 10], [5, 5]), {}, "one level only"),
        (([1, 2], [10, 10], [5, 5]), {"family": "probit"}, "family 'probit'"),
        (([1, 2], [10, 10], [5, 5]), {"lapse": 0.3}, "lapse rate 0.3"),
    ],
)
def test_bad_data_is_one_line(args, kw, match):
    with pytest.raises(UserError, match=match) as e:
        pm.fit(*args, n_boot=0, **kw)
    assert "\n" not in str(e.value)
    with pytest.raises(UserError, match="row 1: correct = 'yes'"):
        pm.fit_trials([{"level_db": 1.0, "correct": True}, {"level_db": 2.0, "correct": "yes"}])
