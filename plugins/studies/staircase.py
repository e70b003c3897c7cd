"""Transformed up-down staircases and their interleaving (pure; rebuilt by replaying).

``Staircase``: ``down`` correct answers in a row lower the level by the step, one wrong
answer raises it (1-up-2-down converges on 70.7 % correct, 1-up-3-down on 79.4 %; Levitt
1971). The step starts at ``step_db`` and halves at each of the first ``halve_after``
reversals (never below ``min_step_db``). A reversal is a move against the previous move;
its level is the level of the trial whose answer turned the track. The track stops after
``stop_reversals`` reversals or ``max_trials`` trials; its threshold is the mean of the
last ``threshold_reversals`` reversal levels. Levels stay in ``[lo_db, hi_db]`` (``hi_db``:
the gate's largest level for the stimulus).

State is only the answers given: ``Staircase.replay(answers)`` rebuilds it exactly, which
is how a resume continues (the trial log holds the answers).

``pick_track(seed, trial, names)``: the staircase of an interleaved trial, a seeded choice
among the tracks still running (the same seed and trial give the same track).
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Staircase:
    down: int = 2
    start_db: float = 0.0
    step_db: float = 4.0
    halve_after: int = 2
    min_step_db: float = 0.5
    stop_reversals: int = 12
    max_trials: int = 80
    threshold_reversals: int = 8
    lo_db: float = -math.inf
    hi_db: float = math.inf
    levels: list[float] = field(default_factory=list)  # each trial's level
    answers: list[bool] = field(default_factory=list)  # each trial's correct (or yes)
    reversal_levels: list[float] = field(default_factory=list)
    reversal_trials: list[int] = field(default_factory=list)
    _level: float = math.nan
    _run: int = 0  # correct answers in a row since the last move
    _last_move: int = 0  # -1 down, +1 up, 0 none yet

    def __post_init__(self) -> None:
        if not math.isfinite(self._level):
            self._level = self.clamp(self.start_db)

    def clamp(self, x: float) -> float:
        return float(min(max(x, self.lo_db), self.hi_db))

    @property
    def step(self) -> float:
        """The step now: halved at each of the first ``halve_after`` reversals."""
        k = min(len(self.reversal_levels), self.halve_after)
        return max(self.step_db / 2**k, self.min_step_db)

    @property
    def level_db(self) -> float:
        """The level of the next trial."""
        return self._level

    @property
    def done(self) -> bool:
        return (
            len(self.reversal_levels) >= self.stop_reversals or len(self.answers) >= self.max_trials
        )

    def update(self, correct: bool) -> None:
        """The answer at ``level_db``; moves the level by the rule."""
        x = self._level
        self.levels.append(x)
        self.answers.append(bool(correct))
        move = 0
        if correct:
            self._run += 1
            if self._run >= self.down:
                move, self._run = -1, 0
        else:
            move, self._run = 1, 0
        if move:
            if self._last_move and move != self._last_move:
                self.reversal_levels.append(x)
                self.reversal_trials.append(len(self.answers) - 1)
            self._last_move = move
            self._level = self.clamp(x + move * self.step)

    def replay(self, answers: list[bool]) -> Staircase:
        """This staircase after ``answers`` (from its start)."""
        for a in answers:
            self.update(a)
        return self

    def threshold_db(self) -> float:
        """Mean of the last ``threshold_reversals`` reversal levels (NaN with fewer than
        two reversals; all of them when there are fewer)."""
        r = self.reversal_levels[-self.threshold_reversals :]
        return float(np.mean(r)) if len(r) >= 2 else math.nan

    def converged_trials(self, skip_reversals: int | None = None) -> list[int]:
        """Trial indices from the ``skip_reversals``-th reversal on (default: the reversals
        the threshold does not use), the part of the track that has converged."""
        n = len(self.reversal_levels)
        k = max(n - self.threshold_reversals, 0) if skip_reversals is None else skip_reversals
        if k >= n:
            return []
        return list(range(self.reversal_trials[k], len(self.answers)))


def pick_track(seed: int, trial: int, names: list[str]) -> str:
    """The track of an interleaved trial: a seeded uniform choice among ``names``."""
    if not names:
        raise ValueError("no track is running")
    h = hashlib.sha256(f"{int(seed)}:{int(trial)}:track".encode()).digest()
    rng = np.random.default_rng(int.from_bytes(h[:8], "big"))
    return names[int(rng.integers(len(names)))]


def target_interval(seed: int, trial: int, n_intervals: int) -> int:
    """The interval (0-based) holding the target of a trial: seeded, uniform."""
    h = hashlib.sha256(f"{int(seed)}:{int(trial)}:interval".encode()).digest()
    return int(np.random.default_rng(int.from_bytes(h[:8], "big")).integers(n_intervals))
