"""A CLI command ends when its table is e-stopped from elsewhere (`haptable estop`, the
console's ctrl+e, a fault): ``RemoteStop(outputs)`` raises ``KeyboardInterrupt`` in the
main thread (its sleeps and waits wake up); ``reason`` says why."""

from __future__ import annotations

import signal
import threading
from typing import Any

_SIGNAL = signal.SIGUSR1
_pending = False
_handler_installed = False


class RemoteStop:
    """Listens to ``outputs`` (``console.kernel.client.Outputs``) for an e-stop."""

    def __init__(self, outputs: Any) -> None:
        self._outputs = outputs
        self._woken = False
        self._lock = threading.Lock()
        self._armed = threading.current_thread() is threading.main_thread()
        if self._armed:
            _install_handler()
        outputs.add_listener(self._on_event)

    @property
    def reason(self) -> str | None:
        """Why the table was e-stopped while the command ran (None: it was not)."""
        return self._outputs.estopped_by

    def _on_event(self, kind: str, message: str) -> None:
        global _pending
        if kind != "estop":
            return
        with self._lock:
            if self._woken:
                return
            self._woken = True
            if self._armed:
                _pending = True
                signal.pthread_kill(threading.main_thread().ident, _SIGNAL)

    def disarm(self) -> None:
        global _pending
        with self._lock:
            self._armed = False
            _pending = False


def _on_signal(signum, frame) -> None:
    global _pending
    if _pending:
        _pending = False
        raise KeyboardInterrupt


def _install_handler() -> None:
    global _handler_installed
    if not _handler_installed:
        signal.signal(_SIGNAL, _on_signal)
        _handler_installed = True
