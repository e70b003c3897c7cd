"""The console session: outputs and their hand-over, the control server, e-stop and play.

The camera service, vibration session, demo lifecycle and projector service hang off the
session as attributes (``camera``, ``vibration``, ``demos``, ``projector``), each in its own
module of this package. Blocking calls (open, hand over, play, close) run on the caller's
thread: screens call them from workers.
"""

from __future__ import annotations

import contextlib
import os
import threading
from collections.abc import Callable
from typing import Any

from console.errors import SafetyRefusal, UserError
from console.session.events import Failed, SessionEvent, Started, Stopped

Subscriber = Callable[[SessionEvent], None]


class ConsoleSession:
    """What one operator's console runs: ``ctx`` gives the profile (``ctx.profile``) and the
    plugins (``ctx.pm``); ``fast`` runs the twin's outputs unpaced (tests)."""

    def __init__(self, ctx: Any, *, fast: bool | None = None) -> None:
        self.ctx = ctx
        self.fast = fast
        self.outputs: Any = None
        self.outputs_error = ""
        self.played: list = []  # OutputPlans accepted for playing (the twin log lists them)
        self._control: Any = None
        self._lock = threading.Lock()
        self._subscribers: list[Subscriber] = []
        self.closed = False

    @property
    def profile(self) -> Any:
        return self.ctx.profile

    @property
    def plugins(self) -> Any:
        return self.ctx.pm

    # ------------------------------------------------------------------ observers
    def subscribe(self, fn: Subscriber) -> None:
        """Call ``fn(event)`` for everything the session reports (from any thread)."""
        self._subscribers.append(fn)

    def emit(self, event: SessionEvent) -> None:
        for fn in list(self._subscribers):
            with contextlib.suppress(Exception):  # an observer never breaks the session
                fn(event)

    def fail(self, topic: str, message: str, *, name: str = "", severity: str = "error") -> None:
        self.emit(Failed(topic, name, message=message, severity=severity))

    # ------------------------------------------------------------------ outputs
    def open_outputs(self, estop_reason: str | None = None) -> bool:
        """Open the profile's outputs (again after a demo: ``estop_reason`` keeps an e-stop
        that happened meanwhile until the operator resets it). Blocking. The first call
        also takes the console's control socket: a second console opens no outputs."""
        from console.runtime.control import ControlServer
        from console.runtime.outputs import open_outputs

        if self.closed:
            return False
        if self._control is None:
            try:
                self._control = ControlServer(self.profile, self._control_command)
            except (OSError, UserError) as exc:
                self.outputs_error = str(exc)
                self.emit(Stopped("outputs", reason=self.outputs_error))
                return False
        try:
            out = open_outputs(self.profile, self.plugins, fast=self.fast)
        except Exception as exc:  # noqa: BLE001 - shown in the bar; the console stays usable
            self.outputs_error = str(exc)
            self.emit(Stopped("outputs", reason=self.outputs_error))
            return False
        if estop_reason:
            out.estop(estop_reason)
        with self._lock:
            if self.closed:  # closed while opening: nobody will close these
                out.close()
                return False
            self.outputs = out
            self.outputs_error = ""
        self.emit(Started("outputs"))
        return True

    def hand_over_outputs(self, borrower: str) -> None:
        """Close the console's outputs for ``borrower`` (a demo process opens them: a sound
        card or relay board opens once). Refused while they play or are e-stopped.
        Blocking; ``open_outputs`` takes them back."""
        with self._lock:
            out = self.outputs
            if out is None:
                raise UserError(
                    f"{borrower}: outputs not open ({self.outputs_error or 'starting'})"
                )
            if out.gate.estopped:
                raise UserError(f"{borrower}: the e-stop is active; ctrl+r resets it")
            if out.status()["busy"]:
                raise UserError(f"{borrower}: the outputs are playing; wait or stop them (s)")
            self.outputs = None
            self.outputs_error = f"in use by {borrower} (its own process)"
        out.close()
        self.emit(Stopped("outputs", reason=self.outputs_error))

    def _control_command(self, line: str) -> str:
        if line == "estop":
            self.estop("e-stop from another process")
            return "ok: outputs silenced, relays open"
        return f"error: unknown command {line!r}"

    def play_plan(self, plan: Any, *, wait: bool = True) -> bool:
        """Play ``plan`` through the safety gate (blocking when ``wait``). A refusal or an
        error is reported as a ``Failed`` event; returns True when it played (or queued)."""
        out = self.outputs
        if out is None:
            self.fail("outputs", f"outputs not open: {self.outputs_error or 'starting'}")
            return False
        try:
            report = out.play(plan, wait=False)
            with self._lock:
                self.played.append(plan)
            if wait:
                report.wait(3 * plan.duration_s + 10)
                if report.error:
                    raise SafetyRefusal(f"{report.name}: {report.error}")
        except (SafetyRefusal, UserError) as exc:
            self.fail("outputs", str(exc), name="refused")
            return False
        return True

    def estop(self, reason: str) -> None:
        """Silence every output now: the console's own, or every process holding outputs
        (a demo process) when the console has handed its outputs over."""
        out = self.outputs
        if out is not None:
            out.estop(reason)
        else:
            from console.safety import estop_all

            estop_all(reason)
        self.emit(Stopped("estop", reason=reason))

    def reset_estop(self) -> bool:
        out = self.outputs
        if out is not None and out.gate.estopped:
            out.reset()
            return True
        return False

    def output_status(self) -> tuple[dict | None, Any]:
        """(status, relay log) of the outputs: the console's, else what the running demo
        process last said of its own (status None: nobody holds them)."""
        out = self.outputs
        if out is not None:
            return out.status(), out.relay_log()
        return None, None

    # ------------------------------------------------------------------ exit
    def close(self) -> None:
        """Stop everything the session runs and close the outputs (blocking: the app calls
        it from a worker at quit). Idempotent."""
        with self._lock:
            if self.closed:
                return
            self.closed = True
        if self._control is not None:
            with contextlib.suppress(Exception):
                self._control.close()
        out = self.outputs
        if out is not None:
            path = os.environ.get("HAPTABLE_TWIN_LOG")
            if path:
                from console.runtime.twin_log import write_twin_log

                with contextlib.suppress(Exception):  # never block the shutdown
                    write_twin_log(path, out, list(self.played))
            out.close()
