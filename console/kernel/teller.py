"""The outputs' listeners told on a thread of their own (``Teller``).

An e-stop, a reset or a fault reaches ``console.kernel.client.Outputs`` on its reader
thread; its listeners (the console's screens, a study run) may call the outputs back, so
they are told on another thread, in order. That thread starts with the first event and,
once the outputs are closed, ends when nothing is left to tell (a later event starts one
again): a console that opens its outputs again and again keeps no thread per opening.
"""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Callable

#: how long a closed teller's thread waits for a last event before it ends
LINGER_S = 0.5


class Teller:
    """``tell(kind, message)`` to every listener, in order, off the caller's thread."""

    def __init__(self, name: str = "haptable-kernel-events") -> None:
        self.listeners: list[Callable[[str, str], None]] = []
        self._name = name
        self._told: queue.SimpleQueue = queue.SimpleQueue()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()
        self._closed = False

    @property
    def thread(self) -> threading.Thread | None:
        """The thread telling now (None between events once closed)."""
        return self._thread

    def tell(self, kind: str, message: str) -> None:
        if not self.listeners:
            return
        self._told.put((kind, message))
        with self._lock:
            if self._thread is None:
                self._thread = threading.Thread(target=self._loop, name=self._name, daemon=True)
                self._thread.start()

    def close(self) -> None:
        """The thread ends once the events told before are out."""
        self._closed = True
        self._told.put(None)  # wakes the thread to see it closed

    def _loop(self) -> None:
        while True:
            try:
                item = self._told.get(timeout=LINGER_S if self._closed else None)
            except queue.Empty:
                with self._lock:
                    if self._told.empty():
                        self._thread = None
                        return
                continue
            if item is None:
                continue
            kind, message = item
            for fn in list(self.listeners):
                try:
                    fn(kind, message)
                except Exception:  # a listener never breaks the link
                    logging.getLogger("haptable.outputs").exception("listener failed")
