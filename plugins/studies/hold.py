"""A study run from the command line holds the table's outputs: a participant's run is
never mixed with another process's sounds (the console's auditions, `haptable play`
from another shell), and the refusal they get names the run."""

from __future__ import annotations

import os
from typing import Any

from console.plugin_api import SafetyRefusal, TableBusy, UserError


def hold_for_run(outputs: Any, study: str) -> None:
    """Hold ``outputs`` (the table's kernel client) for this process's study run until it
    leaves; outputs without a kernel (nothing else plays through them) need no hold."""
    hold = getattr(outputs, "hold", None)
    if hold is None:
        return
    try:
        hold(f"a study run of {study} (haptable study run, pid {os.getpid()})")
    except TableBusy:
        raise  # another run holds them: the table's state (exit 5), not bad input
    except SafetyRefusal as exc:
        raise UserError(str(exc)) from None
