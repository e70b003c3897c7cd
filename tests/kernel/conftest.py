"""Load the runtime's plugins (demos, tuio) with the built-ins, whether listed there or not."""

from __future__ import annotations

import socket
import time

import pytest


@pytest.fixture
def plugins():
    import plugins.demos
    import plugins.tuio
    from console.config.plugins import BUILTIN_PLUGINS, load_plugins

    mine = {"demos": plugins.demos, "tuio": plugins.tuio}
    listed = set(BUILTIN_PLUGINS)
    return load_plugins(extra={k: v for k, v in mine.items() if k not in listed})


def connect(path, timeout_s: float = 2.0) -> socket.socket:
    """A client connection; a backlog nobody accepts from is a failure, not a hang."""
    t_end = time.monotonic() + timeout_s
    while True:
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.settimeout(timeout_s)
        try:
            s.connect(str(path))
            return s
        except BlockingIOError:  # the backlog is full right now
            s.close()
            if time.monotonic() > t_end:
                raise TimeoutError(f"{path}: nobody accepts connections") from None
            time.sleep(0.005)
