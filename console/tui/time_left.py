"""The console's time-left rule for the TUI: ``console.core.time_left`` (pure, shared
with the runtime and plugins), under the name the screens import."""

from console.core.time_left import (
    MIN_ELAPSED_S,
    MIN_FRACTION,
    RISE_S,
    RISE_SHARE,
    JobLeft,
    Pace,
    Steady,
    left_words,
    seconds_left,
)

__all__ = [
    "MIN_ELAPSED_S",
    "MIN_FRACTION",
    "RISE_S",
    "RISE_SHARE",
    "JobLeft",
    "Pace",
    "Steady",
    "left_words",
    "seconds_left",
]
