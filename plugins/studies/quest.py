"""QUEST+ (Watson 2017) over a declared psychometric family, with ``questplus``.

``QuestTrack(family=, task=, stim_db=, thresholds_db=, slopes=, lapses=, guess=)``: the
stimulus grid (dB, already cut at the gate's largest level), the parameter grids
(threshold dB, slope, lapse; the guess fixed by the task: 1/2 in 2AFC, 1/3 in 3AFC, the
``guess`` grid of false-alarm rates in yes/no), a uniform prior. ``level_db`` is the
stimulus that minimises the expected entropy of the posterior, ``update(level_db,
correct)`` multiplies in the likelihood of the answer, ``posterior`` is the normalised
posterior over (threshold, slope, guess, lapse), ``threshold_db()`` its mean threshold
and ``ci_db()`` the central 95 % of its marginal.

The likelihood table is ``questplus``'s (``QuestPlus(func="weibull", stim_scale="dB")``);
``weibull_linear`` is its ``stim_scale="linear"``; ``logistic`` replaces it by ``adaptive_pf.p_correct`` on the same grids (``questplus`` has
no logistic). The update and the entropy minimiser are the same formulas as
``questplus.QuestPlus.update`` / ``next_stim`` in plain numpy (seven times faster than
its xarray code); ``tests/studies/test_adaptive_procedures.py`` checks them step for step
against ``questplus``. A track is rebuilt exactly by replaying its (level, answer) pairs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import adaptive_pf as pf

OUTCOMES = ("correct", "incorrect")
PARAMS = ("threshold", "slope", "lower_asymptote", "lapse_rate")


def make_questplus(family: str, stim_db, thresholds_db, slopes, guess, lapses) -> Any:
    """The ``questplus.QuestPlus`` of these grids (its likelihoods set for ``family``)."""
    # lazy: questplus (and xarray) load only when a QUEST+ track starts
    import questplus

    qp = questplus.QuestPlus(
        stim_domain={"intensity": np.asarray(stim_db, float)},
        param_domain=dict(zip(PARAMS, (thresholds_db, slopes, guess, lapses), strict=True)),
        outcome_domain={"response": list(OUTCOMES)},
        func="weibull",
        stim_scale="linear" if family == "weibull_linear" else "dB",
        stim_selection_method="min_entropy",
        param_estimation_method="mean",
    )
    if family == "logistic":
        lik = qp.likelihoods
        names = lik.dims[1:]
        grids = dict(
            zip(
                names,
                np.meshgrid(*(lik.coords[k].values for k in names), indexing="ij"),
                strict=True,
            )
        )
        p = pf.p_correct(
            grids["intensity"],
            "logistic",
            grids["threshold"],
            grids["slope"],
            grids["lower_asymptote"],
            grids["lapse_rate"],
        )
        qp.likelihoods = lik.copy(data=np.stack([p, 1.0 - p]))
    elif family not in ("weibull", "weibull_linear"):
        raise ValueError(f"family {family!r}: use one of {', '.join(pf.FAMILIES)}")
    return qp


@dataclass
class QuestTrack:
    family: str
    task: str
    stim_db: np.ndarray
    thresholds_db: np.ndarray
    slopes: np.ndarray
    lapses: np.ndarray
    guess: np.ndarray | None = None  # yes/no: the false-alarm grid
    max_trials: int = 50
    levels: list[float] = field(default_factory=list)
    answers: list[bool] = field(default_factory=list)
    _lik: Any = None  # (2, stimuli, parameters): P(correct), P(incorrect)
    _post: Any = None  # (parameters,)
    _next: float | None = None

    def __post_init__(self) -> None:
        if self.task in pf.GUESS:
            self.guess = np.array([pf.GUESS[self.task]])
        else:
            self.guess = np.atleast_1d(self.guess if self.guess is not None else 0.0)
        self.stim_db = np.asarray(self.stim_db, float)
        qp = make_questplus(
            self.family, self.stim_db, self.thresholds_db, self.slopes, self.guess, self.lapses
        )
        lik = qp.likelihoods.transpose("response", "intensity", *PARAMS).values
        self._lik = np.ascontiguousarray(lik.reshape(2, self.stim_db.size, -1))
        self._post = np.full(self._lik.shape[2], 1.0 / self._lik.shape[2])
        self.shape = tuple(len(np.atleast_1d(g)) for g in self.grids())

    def grids(self) -> tuple[np.ndarray, ...]:
        """The parameter grids in the posterior's axis order."""
        return (
            np.asarray(self.thresholds_db, float),
            np.asarray(self.slopes, float),
            np.asarray(self.guess, float),
            np.asarray(self.lapses, float),
        )

    @property
    def level_db(self) -> float:
        """The next level: the expected-entropy minimiser (``questplus``'s
        ``min_entropy``; the first of equal ones)."""
        if self._next is None:
            joint = self._lik * self._post[None, None, :]
            pk = joint.sum(axis=-1)
            with np.errstate(divide="ignore", invalid="ignore"):
                new = joint / pk[..., None]
                h = -np.nansum(new * np.log(new), axis=-1)
            self._next = float(self.stim_db[int(np.argmin((pk * h).sum(axis=0)))])
        return self._next

    @property
    def done(self) -> bool:
        return len(self.answers) >= self.max_trials

    def update(self, level_db: float, correct: bool) -> None:
        """The answer at ``level_db`` (taken to the nearest level of the grid)."""
        k = int(np.argmin(np.abs(self.stim_db - level_db)))
        post = self._post * self._lik[0 if correct else 1, k]
        self._post = post / post.sum()
        self.levels.append(float(self.stim_db[k]))
        self.answers.append(bool(correct))
        self._next = None

    def replay(self, pairs: list[tuple[float, bool]]) -> QuestTrack:
        for x, a in pairs:
            self.update(x, a)
        return self

    @property
    def posterior(self) -> np.ndarray:
        """The posterior over (threshold, slope, guess, lapse), float64, sums to 1."""
        return self._post.reshape(self.shape)

    def marginal_threshold(self) -> np.ndarray:
        return self.posterior.sum(axis=(1, 2, 3))

    def threshold_db(self) -> float:
        """The posterior mean threshold (dB)."""
        return float(np.dot(self.marginal_threshold(), self.grids()[0]))

    def ci_db(self, mass: float = 0.95) -> tuple[float, float]:
        """The central ``mass`` of the threshold's marginal posterior (grid levels)."""
        t = self.grids()[0]
        c = np.cumsum(self.marginal_threshold())
        lo = t[min(int(np.searchsorted(c, (1 - mass) / 2)), t.size - 1)]
        hi = t[min(int(np.searchsorted(c, 1 - (1 - mass) / 2)), t.size - 1)]
        return float(lo), float(hi)
