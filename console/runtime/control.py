"""The console's command channel, and "one console at a time" per user and profile.

A console holds an exclusive lock on ``console-<profile>-<key>.lock`` in the private
runtime directory (``console.kernel.private_dir``) while it runs: the lock ends with the
process, so the socket of a console that died is never taken for another console. Beside
it, ``console-<profile>-<key>.sock`` (0600, ``console.kernel.line_server``: bounded lines,
a deadline per connection, peers of this uid only) answers ``ping`` and ``estop`` (which
also stops what the console's screens run). The outputs themselves are reached by
`haptable estop` through ``console.runtime.outputs_registry``, like any process's.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from collections.abc import Callable
from pathlib import Path

from console.core.errors import UserError
from console.kernel.line_server import LineServer, PeerRefused, request
from console.kernel.private_dir import open_private
from console.kernel.tables import table_for


def socket_path(profile) -> Path:
    return table_for(profile.path).ensure().dir / "console.sock"


def send_command(profile, command: str, timeout_s: float = 1.0) -> str | None:
    """Send one line to a running console; its reply, or None if none answers (none runs,
    it does not answer in time, or the socket is not this user's)."""
    try:
        return request(socket_path(profile), command, timeout_s=timeout_s)[0] or None
    except (OSError, UserError):
        return None


def _holder(lock_path: Path) -> str:
    with contextlib.suppress(OSError, ValueError):
        fd = os.open(lock_path, os.O_RDONLY | os.O_NOFOLLOW)
        with os.fdopen(fd) as f:
            return f" (pid {int(f.read(32).strip())})"
    return ""


def holder_of(profile) -> str:
    """`` (pid N)``: the console holding ``profile``'s lock, as its lock file says
    ("" when unknown)."""
    return _holder(table_for(profile.path).console_lock)


class ControlServer:
    """Serves ``ping`` and the console's commands to other processes; refuses (``UserError``)
    when another console of this user already runs the profile."""

    def __init__(self, profile, handler: Callable[[str], str]):
        self.path = socket_path(profile)
        self.lock_path = table_for(profile.path).console_lock
        self.handler = handler
        self._lock_fd = open_private(self.lock_path, append=True)
        try:
            fcntl.flock(self._lock_fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(self._lock_fd)
            raise UserError(
                f"another console already runs profile {profile.name!r}"
                f"{_holder(self.lock_path)}; use it, or quit it first"
            ) from None
        try:
            os.ftruncate(self._lock_fd, 0)
            os.write(self._lock_fd, f"{os.getpid()}\n".encode())
            self._remove_stale()
            self._server = LineServer(self.path, self._command, name="haptable-control")
        except BaseException:
            os.close(self._lock_fd)
            raise

    def _remove_stale(self) -> None:
        """With the lock held, a socket file here is a dead console's: remove it (after
        making sure nothing of ours answers on it)."""
        try:
            reply = request(self.path, "ping", timeout_s=0.2)[0]
        except (FileNotFoundError, ConnectionRefusedError, PeerRefused, TimeoutError, OSError):
            reply = None
        if reply == "pong":  # cannot happen while we hold the lock; never take it over
            raise UserError(f"another console answers on {self.path}; quit it first")
        with contextlib.suppress(FileNotFoundError):
            os.unlink(self.path)

    def _command(self, line: str, peer_pid: int) -> str:
        return "pong" if line == "ping" else self.handler(line)

    def close(self) -> None:
        """Stop serving, remove the socket, release the lock. Safe to call twice."""
        if self._lock_fd < 0:
            return
        try:
            self._server.close()
        finally:
            os.close(self._lock_fd)
            self._lock_fd = -1
