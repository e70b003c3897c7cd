"""E-stop every live gate of this process: on exit, SIGINT/SIGTERM and any unhandled
exception (``install_emergency_hooks``), or when asked (``estop_all``)."""

from __future__ import annotations

import atexit
import logging
import signal
import sys
import threading

from console.safety.gate import LIVE_GATES

log = logging.getLogger("haptable.safety")

_installed = False


def estop_all(reason: str) -> None:
    for gate in list(LIVE_GATES):
        try:
            gate.estop(reason)
        except Exception:
            log.exception("e-stop failed")


def install_emergency_hooks() -> None:
    """E-stop every live gate on exit, SIGINT/SIGTERM and any unhandled exception."""
    global _installed
    if _installed:
        return
    _installed = True
    atexit.register(estop_all, "exit")

    prev_excepthook = sys.excepthook

    def excepthook(tp, value, tb):
        estop_all(f"unhandled exception: {tp.__name__}: {value}")
        prev_excepthook(tp, value, tb)

    sys.excepthook = excepthook
    prev_thread_hook = threading.excepthook

    def thread_hook(args):
        estop_all(
            f"unhandled exception in thread {args.thread.name if args.thread else '?'}: "
            f"{args.exc_type.__name__}: {args.exc_value}"
        )
        prev_thread_hook(args)

    threading.excepthook = thread_hook

    if threading.current_thread() is not threading.main_thread():
        return
    for sig in (signal.SIGINT, signal.SIGTERM):
        prev = signal.getsignal(sig)

        def handler(signum, frame, _prev=prev):
            estop_all(f"signal {signal.Signals(signum).name}")
            if callable(_prev):
                _prev(signum, frame)
            elif signum == signal.SIGINT:
                raise KeyboardInterrupt
            else:
                raise SystemExit(128 + signum)

        signal.signal(sig, handler)
