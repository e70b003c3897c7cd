"""Psychometric functions in dB and the tasks' guess rates (pure numpy).

A family ``F(x)`` of the level ``x`` (dB) with threshold ``t`` (dB) and slope ``beta``:

- ``weibull``: ``F = 1 - exp(-10^(beta (x - t) / 20))`` (QUEST+'s Weibull on a dB scale,
  ``questplus.psychometric_function.weibull(scale="dB")``; ``F(t) = 1 - 1/e``);
- ``logistic``: ``F = 1 / (1 + 10^(-beta (x - t) / 20))`` (``F(t) = 1/2``);
- ``weibull_linear``: ``F = 1 - exp(-(x / t)^beta)`` for ``x >= 0`` (``scale="linear"``):
  for an increment ``x`` in dB over a reference (a JND), where ``F(0) = 0``.

The probability of a correct answer (n-AFC) or of "yes" (yes/no) is
``p = guess + (1 - guess - lapse) F``; ``guess`` is fixed by the task (``GUESS``: 1/2 in
2AFC, 1/3 in 3AFC) and is the false-alarm rate in yes/no. ``level_at(p, ...)`` inverts it.
"""

from __future__ import annotations

import math

import numpy as np

FAMILIES = ("weibull", "logistic", "weibull_linear")
TASKS = ("yes_no", "2afc", "3afc")
#: the guess rate of each forced-choice task (yes/no: the observer's false-alarm rate)
GUESS = {"2afc": 1 / 2, "3afc": 1 / 3}
#: the intervals of a trial per task
INTERVALS = {"yes_no": 1, "2afc": 2, "3afc": 3}


def core(x_db, family: str, threshold_db, slope):
    """``F(x)`` of the family (module docstring), broadcast over its arguments."""
    if family == "weibull_linear":
        r = np.maximum(np.asarray(x_db, float), 0.0) / np.asarray(threshold_db, float)
        return -np.expm1(-np.power(r, np.asarray(slope, float)))
    z = np.asarray(slope, float) * (np.asarray(x_db, float) - np.asarray(threshold_db, float))
    if family == "weibull":
        return -np.expm1(-np.power(10.0, np.clip(z / 20.0, -30, 30)))
    if family == "logistic":
        return 1.0 / (1.0 + np.power(10.0, np.clip(-z / 20.0, -30, 30)))
    raise ValueError(f"family {family!r}: use one of {', '.join(FAMILIES)}")


def p_correct(x_db, family: str, threshold_db, slope, guess, lapse):
    """``guess + (1 - guess - lapse) F(x)``."""
    g = np.asarray(guess, float)
    return g + (1.0 - g - np.asarray(lapse, float)) * core(x_db, family, threshold_db, slope)


def level_at(p: float, family: str, threshold_db: float, slope: float, guess: float, lapse: float):
    """The level (dB) where ``p_correct`` is ``p`` (NaN when ``p`` is out of its range)."""
    f = (p - guess) / (1.0 - guess - lapse)
    if not 0.0 < f < 1.0:
        return math.nan
    if family == "weibull_linear":
        return threshold_db * (-math.log1p(-f)) ** (1.0 / slope)
    if family == "weibull":
        u = math.log10(-math.log1p(-f))
    elif family == "logistic":
        u = -math.log10(1.0 / f - 1.0)
    else:
        raise ValueError(f"family {family!r}: use one of {', '.join(FAMILIES)}")
    return threshold_db + 20.0 * u / slope


def staircase_target(down: int) -> float:
    """The proportion correct an ``down``-down/1-up staircase converges on (Levitt 1971):
    ``0.5^(1/down)`` (70.7 % for 2, 79.4 % for 3)."""
    return 0.5 ** (1.0 / down)
