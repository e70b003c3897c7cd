"""Checks of command-line option values, shared by the core's commands and the plugins'."""

from __future__ import annotations

import math

from console.errors import UserError


def seconds_option(value: float | None, flag: str) -> float | None:
    """A duration option (``--seconds``, ``--minutes``, ...) checked: finite and not
    negative (``None``: not given); else a one-line ``UserError``."""
    if value is not None and not (math.isfinite(value) and value >= 0):
        raise UserError(f"{flag} {value!r}: give a finite time, 0 or more")
    return value
