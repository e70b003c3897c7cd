"""A study run from the command line holds the table's outputs: a participant's run is
never mixed with another process's sounds (the console's auditions, `haptable play`
from another shell), and the refusal they get names the run."""

from __future__ import annotations

import atexit
import contextlib
import os
from typing import Any

from console.plugin_api import SafetyRefusal, TableBusy, UserError


def run_words(study: str, simulated: bool = False) -> str:
    """How another process names this one's study run (a simulated one plays on a twin
    of the table, which the table's e-stop stops all the same)."""
    if simulated:
        return (
            f"a simulated study run of {study} (haptable study run --simulate, pid {os.getpid()})"
        )
    return f"a study run of {study} (haptable study run, pid {os.getpid()})"


def hold_map_for_run(profile: Any, study: str, simulated: bool = False) -> None:
    """Hold ``profile``'s vibration map as the Studies screen's runs hold the console's
    (``map_held``: the console's Vibration screen refuses to measure, load or import
    over it, naming this run) until this process ends; ``TableBusy`` (exit 5) while
    another run holds it."""
    # lazy: the runtime part loads on first use, not at every haptable start
    from console.plugin_api.runtime import map_held

    stack = contextlib.ExitStack()
    stack.enter_context(map_held(profile, run_words(study, simulated)))
    atexit.register(stack.close)


def hold_table_for_run(profile: Any, study: str, simulated: bool = False) -> None:
    """Hold ``profile``'s table for this process's study run until it ends, from its
    start (before its map is read): the console of the profile plays nothing meanwhile
    (``table_held``: every play, audition, test signal and demo is refused naming this
    run), a simulated run on its own twin too; ``TableBusy`` (exit 5) while another run
    holds it."""
    # lazy: the runtime part loads on first use, not at every haptable start
    from console.plugin_api.runtime import table_held

    stack = contextlib.ExitStack()
    stack.enter_context(table_held(profile, run_words(study, simulated)))
    atexit.register(stack.close)


def hold_for_run(outputs: Any, study: str, simulated: bool = False) -> None:
    """Hold ``outputs`` (the table's kernel client) for this process's study run until it
    leaves: other processes' plays refused; outputs without a kernel (nothing else plays
    through them) need no such hold."""
    hold = getattr(outputs, "hold", None)
    if hold is None:
        return
    try:
        hold(run_words(study, simulated))
    except TableBusy:
        raise  # another run holds them: the table's state (exit 5), not bad input
    except SafetyRefusal as exc:
        raise UserError(str(exc)) from None
