"""A study run from the command line that the table's e-stop stops (the console's ctrl+e,
`haptable estop`, a fault; a simulated run's twin too: ``ctx.outputs``) leaves with
``EStopped`` (exit 4) and says the trial it stopped and how to go on: the operator's
reset, then the same command resumes there."""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterator
from typing import Any

from console.plugin_api import EStopped
from console.plugin_api.runtime import Stopped

#: the e-stop's abort reason: its key in the console (``console.session.events``)
ESTOP_STOPPED = "stopped by the e-stop ({why}), ctrl+r resets"


class EStopWatch:
    """Aborts a console run (its ``control``) at the table's e-stop, whatever the run
    waits for (an answer, a score, a pause): the session's e-stop event (``Stopped``,
    topic ``estop``) is observed, not the latch, which a reset typed at once clears
    before the run would look. ``reason``: the abort's words once it came ("" before)."""

    def __init__(self, control: Any) -> None:
        self.control = control
        self.reason = ""

    def __call__(self, event: Any) -> None:
        if event.topic == "estop" and isinstance(event, Stopped) and not self.reason:
            self.reason = ESTOP_STOPPED.format(why=" ".join(str(event.reason).split()))
            self.control.abort(self.reason)


def estopped_words(reason: str, trial: int | None) -> str:
    """A console run the e-stop stopped, as a stimulus it stopped says it: the trial."""
    return f"trial {trial}: {reason}" if trial else reason


@contextlib.contextmanager
def estop_aborts(session: Any, control: Any) -> Iterator[EStopWatch]:
    """While the block runs, the table's e-stop aborts ``control`` (``EStopWatch``)."""
    watch = EStopWatch(control)
    stop_watching = session.subscribe(watch)
    try:
        yield watch
    finally:
        if callable(stop_watching):
            stop_watching()


def estop_reason(outputs: Any) -> str | None:
    """Why the table's e-stop stopped these outputs (None: it did not). Its event may come
    after the stimulus it cut ended (two threads of the kernel): the kernel is asked."""
    if outputs.estopped_by:
        return outputs.estopped_by
    try:
        gate = outputs.status()["gate"]
    except Exception:  # noqa: BLE001 - outputs gone: the e-stop's event says it, or nothing
        return outputs.estopped_by
    return (outputs.estopped_by or gate["estop_reason"]) if gate["estopped"] else None


@contextlib.contextmanager
def says_estopped(flight: dict[str, Any], *, quiet: bool = False) -> Iterator[None]:
    """Around ``ctx.outputs``: a run the e-stop stopped (``EStopped``; its interrupt can
    no longer come here) says so. ``flight``, kept by the run: ``pid``, ``trial`` (the
    one under way, from 1) and ``done`` (the words of the trials done: ``15/50``)."""
    try:
        yield
    except EStopped:
        if flight.get("pid") and not quiet:
            done: Callable[[], str] = flight.get("done") or (lambda: "?")
            print(estopped_line(flight["pid"], flight.get("trial"), done()), flush=True)
        raise


def estopped_line(pid: str, trial: int | None, done: str) -> str:
    """What a run the table's e-stop stopped says: the trial it stopped and how to go on."""
    at = f"trial {trial}" if trial else "the run"
    again = f"resumes at trial {trial}" if trial else "resumes"
    return (
        f"{pid}: {at} stopped by the e-stop ({done} trials done); once an operator resets "
        f"it (ctrl+r in the console, or `haptable reset` at a terminal) the same command "
        f"{again}"
    )
