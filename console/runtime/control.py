"""The console's control socket: lets `haptable estop` (another process) stop a console.

A Unix-domain socket per profile under $XDG_RUNTIME_DIR (or the temp dir); one line in,
one line out. No network listener.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import socket
import tempfile
import threading
from collections.abc import Callable
from pathlib import Path


def socket_path(profile) -> Path:
    base = Path(os.environ.get("XDG_RUNTIME_DIR") or tempfile.gettempdir()) / "haptable"
    key = hashlib.sha1(str(profile.path).encode()).hexdigest()[:10]
    return base / f"console-{profile.name}-{key}.sock"


def send_command(profile, command: str, timeout_s: float = 1.0) -> str | None:
    """Send one line to a running console; its reply, or None if none is running."""
    path = socket_path(profile)
    if not path.exists():
        return None
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(timeout_s)
            s.connect(str(path))
            s.sendall(command.encode() + b"\n")
            return s.makefile().readline().strip() or None
    except OSError:
        return None


class ControlServer:
    """Serves commands (``estop``, ``status``) to other processes."""

    def __init__(self, profile, handler: Callable[[str], str]):
        self.path = socket_path(profile)
        self.handler = handler
        self.path.parent.mkdir(parents=True, exist_ok=True, mode=0o700)
        if self.path.exists():
            if send_command(profile, "ping") is not None:
                raise OSError(f"another console already runs this profile ({self.path})")
            self.path.unlink()
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self._sock.bind(str(self.path))
        self._sock.listen(4)
        self._thread = threading.Thread(target=self._serve, name="haptable-control", daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self._sock.accept()
            except OSError:
                return
            with conn:
                try:
                    line = conn.makefile().readline().strip()
                    reply = "pong" if line == "ping" else self.handler(line)
                    conn.sendall(reply.encode() + b"\n")
                except Exception as exc:
                    with contextlib.suppress(OSError):
                        conn.sendall(f"error: {exc}\n".encode())

    def close(self) -> None:
        try:
            self._sock.close()
        finally:
            if self.path.exists():
                self.path.unlink()
