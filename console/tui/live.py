"""The table's output state for the screens, read off the UI thread.

``OutputsWatch`` asks the table's kernel for its status (``Outputs.status``) every
``POLL_S`` on a thread of its own, at once when poked (a session event: an e-stop, a
reset, the outputs opening), and hands the app an ``OutputsChanged`` message only when
something a screen shows has changed (``status_key``: the gate's clock, the audio
blocks counted, the kernel's request counters are left out). The relay log (every
switch of the board, growing) is read only when the board's switch count moved. Idle,
the UI thread does nothing for it.
"""

from __future__ import annotations

import json
import logging
import threading
import time
from typing import Any, Protocol, runtime_checkable

from textual.message import Message

from console.core.errors import SafetyRefusal
from console.kernel.shell import reset_command
from console.kernel.tables import latched_elsewhere, read_latch, table_for

log = logging.getLogger(__name__)

#: how often the kernel is asked for its status (the safety bar's live levels)
POLL_S = 0.1
#: how often the other tables' latches are read (a shell's `haptable estop` latches every
#: table; `haptable reset --profile P` clears one): the bar names those still latched
OTHERS_S = 1.0

#: status fields that change while nothing a screen shows does, by section
_CHURN: dict[str | None, frozenset[str]] = {
    None: frozenset({"latency_samples"}),
    "gate": frozenset({"clock", "quiet_samples"}),
    "audio": frozenset({"blocks", "fill_ms"}),
    "kernel": frozenset({"requests"}),
}


def _shown_v(v: Any) -> float:
    """A level as the bar shows it (0.1 V; what shows as zero is zero)."""
    v = float(v)
    return 0.0 if abs(v) < 0.05 else round(v, 1)


def status_key(status: dict | None, error: str = "") -> str:
    """What the screens show of ``status`` (None: outputs not open, ``error`` why), as a
    string that changes only when that does."""
    if status is None:
        return f"closed:{error}"
    kept: dict[str, Any] = {}
    for k, v in status.items():
        if k in _CHURN[None]:
            continue
        if isinstance(v, dict) and k in _CHURN:
            v = {kk: vv for kk, vv in v.items() if kk not in _CHURN[k]}
        kept[k] = v
    gate = kept.get("gate")
    if isinstance(gate, dict) and "level_v" in gate:
        kept["gate"] = {**gate, "level_v": [_shown_v(x) for x in gate["level_v"]]}
    return json.dumps(kept, sort_keys=True, default=str)


def switches(status: dict | None) -> Any:
    """The relay board's switch count in ``status`` (None: not reported)."""
    relays = (status or {}).get("relays")
    return relays.get("switches") if isinstance(relays, dict) else None


class OutputsChanged(Message, bubble=False):
    """The output state a screen shows changed: ``status`` (None: not open) and the
    relay ``log`` (None: not read, or real hardware); ``latch``: with no outputs open
    here, the table's e-stop (``own_latch``), else None."""

    def __init__(self, status: dict | None, log: Any, latch: dict | None = None) -> None:
        super().__init__()
        self.status = status
        self.log = log
        self.latch = latch


def own_latch(profile_path: str, console_elsewhere: bool) -> dict | None:
    """The e-stop latched on the table of ``profile_path`` while no outputs are open
    here (a second console of the profile, outputs lost or failed): ``{"reason",
    "reset", "short"}``, ``reset`` saying where an operator resets it (in the console
    holding the outputs when ``console_elsewhere``; ``short``: in fewer words); None when
    not latched. With outputs open their gate says the e-stop; this console cannot
    reset it."""
    table = table_for(profile_path)
    rec = read_latch(table)
    if rec is None:
        return None
    command = reset_command(table, None)
    if console_elsewhere:
        where = f"reset: ctrl+r in the console holding the outputs, or `{command}`"
        short = "reset in the console holding the outputs"
    else:
        where = short = f"reset: `{command}` at a terminal"
    return {"reason": str(rec.get("reason") or "e-stop"), "reset": where, "short": short}


class OutputsWatch:
    """Polls ``session``'s outputs on a daemon thread; posts ``OutputsChanged`` to
    ``target`` (the app) when ``status_key`` changes."""

    def __init__(self, session: Any, target: Any, poll_s: float = POLL_S) -> None:
        self.session = session
        self.target = target
        self.poll_s = poll_s
        self.status: dict | None = None  # the newest status read (every poll)
        self.log: Any = None  # the relay log as of ``_log_switches``
        self.polls = 0  # status reads so far
        self.changes = 0  # ``OutputsChanged`` posted so far
        self._key: str | None = None
        self._log_switches: Any = object()  # never equal: the first read fetches it
        self._force = False  # the next read is posted even if nothing changed
        self._others: list[str] = []  # the other tables latched (``latched_elsewhere``)
        self._others_t = -1e9  # when they were last read
        self.latch: dict | None = None  # no outputs here: the table's e-stop (``own_latch``)
        self._latch_t = -1e9  # when it was last read
        self._held_why = ""  # why a play is refused now (``_held``), as last read
        self._held_t: float | None = None  # when
        self._wake = threading.Event()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    def start(self) -> None:
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name="haptable-tui-outputs")
            self._thread.daemon = True
            self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._wake.set()

    def poke(self, force: bool = False) -> None:
        """Read the status now (an event says it changed); ``force``: hand it over
        even if what shows is the same (a screen needs it fresh after a request)."""
        self._force = self._force or force
        self._others_t = -1e9  # an e-stop or a reset: the other tables' latches too
        self._latch_t = -1e9  # and this table's, while no outputs are open here
        self._held_t = None  # and who holds the outputs (a run started or ended)
        self._wake.set()

    def _run(self) -> None:
        while not self._stop.is_set():
            self.poll()
            self._wake.wait(self.poll_s)
            self._wake.clear()

    def poll(self) -> bool:
        """Read the status once; True (and a message posted) if what shows changed."""
        self.polls += 1
        force, self._force = self._force, False
        status = self._read()
        if status is not None:  # the other tables' latches, for the bar; who holds them
            status = {
                **status,
                "latched_elsewhere": self._latched_elsewhere(force),
                "held": self._held(force),
            }
            self.latch = None
        else:  # no gate here to ask: the table's latch says whether it is e-stopped
            self._read_own_latch(force)
        key = status_key(status, self.session.outputs_error or "") + json.dumps(self.latch)
        self.status = status
        if key == self._key and not force:
            return False
        count = switches(status)
        if status is not None and (count is None or count != self._log_switches):
            self.log, self._log_switches = self._read_log(), count
        self._key = key
        self.changes += 1
        try:
            self.target.post_message(OutputsChanged(status, self.log, self.latch))
        except Exception:  # noqa: BLE001 - the app is closing: nobody to tell
            return False
        return True

    def _read(self) -> dict | None:
        out = self.session.outputs
        if out is None:
            return None
        try:
            return out.status()
        except SafetyRefusal:  # the kernel went away: the bar says not open
            return None
        except Exception:  # noqa: BLE001 - logged; the watch goes on
            log.exception("reading the outputs' status")
            return None

    def _read_own_latch(self, now: bool) -> None:
        """``latch`` read again every ``OTHERS_S`` (at once when poked: an e-stop here)."""
        t = time.monotonic()
        if now or t - self._latch_t >= OTHERS_S:
            self._latch_t = t
            try:
                s = self.session
                self.latch = own_latch(str(s.profile.path), s.console_elsewhere)
            except Exception:  # noqa: BLE001 - logged; the bar shows what it knew
                log.debug("reading the table's latch", exc_info=True)

    def _latched_elsewhere(self, now: bool) -> list[str]:
        """The other shared tables latched (read every ``OTHERS_S``, at once when poked
        with ``force``: a reset or an e-stop here)."""
        t = time.monotonic()
        out = self.session.outputs
        if now or t - self._others_t >= OTHERS_S:
            self._others_t = t
            try:
                self._others = latched_elsewhere(out.table) if out is not None else []
            except Exception:  # noqa: BLE001 - logged; the bar shows what it knew
                log.debug("reading the other tables' latches", exc_info=True)
        return self._others

    def _held(self, now: bool) -> str:
        """Why a play or a relay toggle is refused now, the session's one check
        (``held_why``: a run or a demo holds the outputs; "" when none does), read with
        the other tables' latches (every ``OTHERS_S``, at once when poked)."""
        if now or self._held_t is None or time.monotonic() - self._held_t >= OTHERS_S:
            self._held_t = time.monotonic()
            try:
                self._held_why = self.session.held_why()
            except Exception:  # noqa: BLE001 - logged; the screens show what they knew
                log.debug("reading who holds the outputs", exc_info=True)
        return self._held_why

    def _read_log(self) -> Any:
        out = self.session.outputs
        try:
            return None if out is None else out.relay_log()
        except Exception:  # noqa: BLE001 - as above; the log stays as it was
            log.debug("reading the relay log", exc_info=True)
            return self.log


class LiveOutputs:
    """The app's output state for its widgets: the ``watch`` reading it, what shows
    ``now`` (status, relay log) and the safety ``bars`` mounted (each adds itself)."""

    def __init__(self, session: Any, target: Any) -> None:
        self.watch = OutputsWatch(session, target)
        self.now: tuple[dict | None, Any] = (None, None)
        self.latch: dict | None = None  # no outputs here: the table's e-stop (``own_latch``)
        self.bars: set[Any] = set()
        self.session = session

    def error(self) -> str:
        """Why the outputs are not open ('' while they are, or still opening)."""
        return self.session.outputs_error or ""


@runtime_checkable
class LiveHost(Protocol):
    """An app that keeps the output state for its widgets (``HapTableApp``)."""

    live: LiveOutputs


@runtime_checkable
class ShowsState(Protocol):
    """A pane drawn from the output state when it changes."""

    def show_state(self, status: dict, log: Any) -> None: ...


@runtime_checkable
class Hides(Protocol):
    """A pane that stops its timers while hidden."""

    def set_visible(self, shown: bool) -> None: ...


def live_of(app: Any) -> LiveOutputs | None:
    """``app``'s output state, or None for an app that keeps none (a test harness)."""
    return app.live if isinstance(app, LiveHost) else None
