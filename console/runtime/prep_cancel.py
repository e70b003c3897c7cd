"""A stop asked while a demo prepares ends its preparation at once.

A demo host's preparation (the registered factory: the twin camera's process, the
classifier, the flow effects' libraries, the planner's process) is seconds of imports
and process starts with no place between them to look at a flag: a stop that waited for
the next check came 5-8 s late. ``Preparation`` makes every step of the interpreter a
check: while ``armed()``, ``cancel()`` (from the host's command thread) raises
``PreparationCancelled`` in the main thread at once (a signal to that thread, so its
sleeps and waits wake up too), and the preparation leaves through its own ``except`` and
``finally`` clauses (cameras closed, the table left), as the host's SIGTERM way out does.
``reap_children()``: the ``multiprocessing`` processes the preparation started (the
flow planner, an atlas's workers) end with it.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator

#: the signal that carries the cancel to the main thread (``remote_stop`` has SIGUSR1)
SIGNAL = signal.SIGUSR2


class PreparationCancelled(BaseException):
    """The demo's preparation was cancelled (raised in the main thread). Not an
    ``Exception``, as ``KeyboardInterrupt`` is not: a step's ``except Exception`` (one
    line for a camera that failed to open) lets it through, its ``finally`` runs."""


class Preparation:
    """Cancel for a preparation running on the main thread. ``install()`` (on the main
    thread) takes ``SIGNAL``; without it ``cancel()`` only records the wish (``armed()``
    raises on entry), never signals."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._armed = False
        self._asked = False
        self._installed = False

    def install(self) -> None:
        signal.signal(SIGNAL, self._on_signal)
        self._installed = True

    @property
    def asked(self) -> bool:
        return self._asked

    @contextlib.contextmanager
    def armed(self) -> Iterator[None]:
        """The block runs cancellable: ``PreparationCancelled`` at once when cancelled
        before or while it runs."""
        with self._lock:
            if self._asked:
                raise PreparationCancelled
            self._armed = True
        try:
            yield
        finally:
            with self._lock:
                self._armed = False

    def cancel(self) -> None:
        """From any thread: the armed block raises now; later blocks raise on entry."""
        with self._lock:
            self._asked = True
            if not (self._armed and self._installed):
                return
        signal.pthread_kill(threading.main_thread().ident, SIGNAL)

    def _on_signal(self, signum, frame) -> None:
        # no lock here: the main thread may hold it (a handler must not wait for itself);
        # a signal that comes after the block ended is dropped (the stop is seen there)
        if self._armed:
            raise PreparationCancelled


def reap_children(timeout_s: float = 2.0) -> int:
    """Terminate the ``multiprocessing`` children of this process and wait for them
    (bounded); returns how many there were."""
    # lazy: a host that started none has not imported it
    import multiprocessing

    kids = multiprocessing.active_children()
    for p in kids:
        p.terminate()
    for p in kids:
        p.join(timeout_s)
    return len(kids)
