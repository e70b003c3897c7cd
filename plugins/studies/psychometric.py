"""Maximum-likelihood fits of psychometric functions to detection data.

The model is ``adaptive_pf.p_correct`` (the adaptive procedures' own): ``p = guess +
(1 - guess - lapse) F(x)``, ``x`` the level in dB, ``F`` the ``weibull`` or ``logistic``
family with ``threshold_db`` and ``slope``. ``guess`` is fixed by the task (1/2 in 2AFC,
1/3 in 3AFC; yes/no: fitted in ``0 .. MAX_GUESS``, or given); ``lapse`` is fitted in
``0 .. MAX_LAPSE`` (or given).

``fit(levels_db, n_trials, n_correct)`` maximises the binomial likelihood: a coarse grid
over (threshold, log slope, lapse[, guess]) finds the basin, SciPy's bounded L-BFGS-B
polishes it. Confidence intervals: a seeded parametric bootstrap (``n_boot`` data sets
drawn from the fitted function at the same levels and trial counts, each refitted;
percentile intervals). ``fit_trials(rows)`` fits an adaptive run's trials (``level_db``,
``correct`` per row) grouped by level.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from console.plugin_api import UserError

from .adaptive_pf import FAMILIES, GUESS, p_correct

TASKS = ("2afc", "3afc", "yes_no")
MAX_LAPSE = 0.1
MAX_GUESS = 0.5
#: the slope's search range (``adaptive_pf``'s slope: per 20 dB)
SLOPE_RANGE = (0.05, 50.0)
PARAMS = ("threshold_db", "slope", "lapse", "guess")


@dataclass
class Fit:
    """A fitted psychometric function; ``ci`` maps a parameter to ``(lo, hi)``."""

    family: str
    task: str
    threshold_db: float
    slope: float
    lapse: float
    guess: float
    log_likelihood: float
    n_trials: int
    ci: dict[str, tuple[float, float]] = field(default_factory=dict)
    ci_method: str = ""

    def p(self, levels_db: Any) -> np.ndarray:
        """The fitted probability correct (yes) at ``levels_db``."""
        return p_correct(
            levels_db, self.family, self.threshold_db, self.slope, self.guess, self.lapse
        )

    def as_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["ci"] = {k: [float(a), float(b)] for k, (a, b) in self.ci.items()}
        return d


def log_likelihood(x, n, k, family: str, threshold_db, slope, lapse, guess) -> np.ndarray:
    """Binomial log-likelihood (less the binomial coefficients), summed over the last
    axis (the levels) of the broadcast arguments."""
    p = np.clip(p_correct(x, family, threshold_db, slope, guess, lapse), 1e-12, 1 - 1e-12)
    return np.sum(k * np.log(p) + (n - k) * np.log1p(-p), axis=-1)


def _data(levels_db: Any, n_trials: Any, n_correct: Any) -> tuple[np.ndarray, ...]:
    x = np.asarray(levels_db, float).ravel()
    n = np.asarray(n_trials, float).ravel()
    k = np.asarray(n_correct, float).ravel()
    if not (x.size == n.size == k.size) or x.size == 0:
        raise UserError(
            f"psychometric fit: {x.size} levels, {n.size} trial counts, {k.size} correct "
            "counts; give one of each per level"
        )
    if not np.all(np.isfinite(x)):
        raise UserError("psychometric fit: a level is not a finite number of dB; fix the data")
    whole = np.all(n == np.round(n)) and np.all(k == np.round(k))
    if not whole or np.any(n < 1) or np.any(k < 0) or np.any(k > n):
        raise UserError(
            "psychometric fit: each level needs a whole number of trials >= 1 and "
            "0 <= correct <= trials; fix the data"
        )
    if np.unique(x).size < 2:
        raise UserError("psychometric fit: trials at one level only; a fit needs two levels")
    return x, n, k


def _ml(x, n, k, family: str, guess: float | None, lapse: float | None, ftol: float = 1e-13):
    """ML ``[threshold_db, slope, lapse, guess]`` and its log-likelihood."""
    # lazy: SciPy loads only when a fit runs
    from scipy.optimize import minimize

    span = max(float(x.max() - x.min()), 1.0)
    t_bounds = (float(x.min()) - span, float(x.max()) + span)
    ls_bounds = (math.log(SLOPE_RANGE[0]), math.log(SLOPE_RANGE[1]))
    free = [lapse is None, guess is None]
    tg = np.linspace(*t_bounds, 31)
    sg = np.exp(np.linspace(*ls_bounds, 25))
    lg = np.array([0.0, 0.03, 0.1]) if free[0] else np.array([lapse])
    gg = np.array([0.0, 0.1, 0.3, 0.5]) if free[1] else np.array([guess])
    grid = np.meshgrid(tg, sg, lg, gg, indexing="ij")
    ll = log_likelihood(x, n, k, family, *(g[..., None] for g in grid))
    i = np.unravel_index(int(np.argmax(ll)), ll.shape)
    start = [grid[0][i], math.log(grid[1][i])]
    bounds = [t_bounds, ls_bounds]
    for is_free, g, hi in zip(free, grid[2:], (MAX_LAPSE, MAX_GUESS), strict=True):
        if is_free:
            start.append(g[i])
            bounds.append((0.0, hi))

    def unpack(v) -> tuple[float, float, float, float]:
        rest = list(v[2:])
        lam = rest.pop(0) if free[0] else lapse
        gam = rest.pop(0) if free[1] else guess
        return float(v[0]), math.exp(v[1]), float(lam), float(gam)

    def nll(v) -> float:
        return -float(log_likelihood(x, n, k, family, *unpack(v)))

    def nll_grad(v) -> tuple[float, np.ndarray]:
        t, s, lam, gam = unpack(v)
        f, df_dsz = _core_and_slope(x - t, s, family)
        p = np.clip(gam + (1 - gam - lam) * f, 1e-12, 1 - 1e-12)
        dl_dp = k / p - (n - k) / (1 - p)
        scale = (1 - gam - lam) * df_dsz
        grads = [-s * scale, s * (x - t) * scale, -f, 1 - f]  # d p / d(t, log s, lapse, guess)
        on = [True, True, *free]
        g = [float(np.sum(dl_dp * d)) for d, use in zip(grads, on, strict=True) if use]
        ll = np.sum(k * np.log(p) + (n - k) * np.log1p(-p))
        return -float(ll), -np.array(g)

    res = minimize(
        nll_grad,
        np.array(start),
        jac=True,
        method="L-BFGS-B",
        bounds=bounds,
        options={"ftol": ftol, "gtol": 1e-10},
    )
    v = res.x if res.fun <= nll(start) else np.array(start)
    return np.array(unpack(v)), -nll(v)


def _core_and_slope(z: np.ndarray, slope: float, family: str) -> tuple[np.ndarray, np.ndarray]:
    """``F`` at ``z = x - threshold`` and ``dF/d(slope z)`` (``adaptive_pf.core``'s
    families, differentiated; a test checks them against finite differences)."""
    c = math.log(10.0) / 20.0
    u = np.clip(slope * z / 20.0, -30, 30)
    if family == "weibull":
        e = np.power(10.0, u)
        f = -np.expm1(-e)
        return f, np.exp(-e) * e * c
    f = 1.0 / (1.0 + np.power(10.0, -u))
    return f, c * f * (1.0 - f)


def fit(
    levels_db: Sequence[float] | np.ndarray,
    n_trials: Sequence[int] | np.ndarray,
    n_correct: Sequence[int] | np.ndarray,
    *,
    family: str = "weibull",
    task: str = "2afc",
    guess: float | None = None,
    lapse: float | None = None,
    n_boot: int = 200,
    ci_level: float = 0.95,
    seed: int = 0,
) -> Fit:
    """The ML fit of (level dB, trials, correct) per level (module docstring). ``lapse``,
    ``guess``: fixed values (else fitted / the task's); ``n_boot = 0``: no intervals."""
    x, n, k = _data(levels_db, n_trials, n_correct)
    if family not in FAMILIES:
        raise UserError(f"psychometric family {family!r}: use one of {', '.join(FAMILIES)}")
    if task not in TASKS:
        raise UserError(f"psychometric task {task!r}: use one of {', '.join(TASKS)}")
    g = GUESS.get(task) if guess is None else float(guess)
    if g is not None and not 0.0 <= g < 1.0:
        raise UserError(f"guess rate {guess}: give a value in 0 .. 1")
    if lapse is not None and not 0.0 <= lapse <= MAX_LAPSE:
        raise UserError(f"lapse rate {lapse}: give a value in 0 .. {MAX_LAPSE}")
    params, ll = _ml(x, n, k, family, g, lapse)
    out = Fit(family, task, *map(float, params), float(ll), int(n.sum()))
    if n_boot > 0:
        rng = np.random.default_rng(seed)
        p_hat = p_correct(x, family, params[0], params[1], params[3], params[2])
        boots = np.array(
            [
                _ml(x, n, rng.binomial(n.astype(int), p_hat), family, g, lapse, 1e-8)[0]
                for _ in range(n_boot)
            ]
        )
        a = (1.0 - ci_level) / 2 * 100
        out.ci = {
            name: (float(np.percentile(boots[:, j], a)), float(np.percentile(boots[:, j], 100 - a)))
            for j, name in enumerate(PARAMS)
        }
        out.ci_method = (
            f"parametric bootstrap ({n_boot} resamples, seed {seed}, {ci_level:.0%} percentile)"
        )
    return out


def group_trials(rows: Iterable[Mapping[str, Any]]) -> tuple[np.ndarray, ...]:
    """Trial rows (``level_db``, ``correct``) as (levels, trials, correct) per level."""
    counts: dict[float, list[int]] = {}
    for i, r in enumerate(rows):
        lv, c = r.get("level_db"), r.get("correct")
        if isinstance(lv, bool) or not isinstance(lv, (int, float)) or not math.isfinite(lv):
            raise UserError(f"trial row {i}: level_db = {lv!r}: must be a number of dB")
        if not isinstance(c, bool):
            raise UserError(f"trial row {i}: correct = {c!r}: must be true or false")
        nk = counts.setdefault(round(float(lv), 9), [0, 0])
        nk[0] += 1
        nk[1] += int(c)
    lv = np.array(sorted(counts))
    return lv, np.array([counts[v][0] for v in lv]), np.array([counts[v][1] for v in lv])


def fit_trials(rows: Iterable[Mapping[str, Any]], **kw: Any) -> Fit:
    """``fit`` of an adaptive run's trials (``level_db``, ``correct`` per row)."""
    return fit(*group_trials(rows), **kw)
