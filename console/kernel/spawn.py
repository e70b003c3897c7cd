"""Starting a table's kernel process (``python -m console.kernel``) for a client.

The kernel gets its start request on stdin (the table's folder, the profile, pickled, and
the plugins this process was given beyond the installed ones) and answers one line on
stdout: ``ready``, ``busy: ...`` (another client started it meanwhile) or ``error: ...``
(its one-line reason). It runs in a session of its own (its terminal's signals are not an
e-stop), with nothing of the client's inherited but the environment, and outlives it;
its stderr goes to ``kernel.log`` in the table's folder.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import select
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

from console.kernel.forkserver import send_request
from console.kernel.operator import stat_fields
from console.kernel.private_dir import open_private
from console.kernel.tables import Table

#: how long a client waits for a kernel it started to say it is ready
START_TIMEOUT_S = 30.0


def log_path(table: Table) -> str:
    return str(table.dir / "kernel.log")


def spawn_kernel(
    table: Table, profile: Any, *, fast: bool, owner: int | None, plugins: Any = None
) -> str:
    """Start the table's kernel; its first line: ``ready``, ``busy: ...`` (another one
    started meanwhile) or ``error: ...``. This process's second kernel and later ones
    come from its fork server (``console.kernel.forkserver``) when it can."""
    table.ensure()
    log_fd = open_private(log_path(table), append=True)
    blob = pickle.dumps(
        {
            "table_dir": str(table.dir),
            "profile": profile,
            "fast": fast,
            "owner": owner,
            # plugins this process was given beyond the installed ones (their drivers)
            "extra_plugins": list(plugins.extra_modules if plugins is not None else ()),
        }
    )
    env = dict(os.environ)
    env.pop("HAPTABLE_TWIN_LOG", None)  # the clients write their own
    try:
        started = _STARTER.start(blob, env, log_fd)
        if started is None:
            started = _interpreter(blob, env, log_fd)
    finally:
        os.close(log_fd)
    return _start_line(table, *started)


def _interpreter(blob: bytes, env: dict, log_fd: int) -> tuple[int, Callable[[], int | None]]:
    """``python -m console.kernel`` in a fresh interpreter: (its stdout, how it ended)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "console.kernel"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=log_fd,
        start_new_session=True,  # its terminal's signals are not an e-stop
        close_fds=True,
        env=env,
    )
    try:
        proc.stdin.write(f"{len(blob)}\n".encode() + blob)
        proc.stdin.close()
    except BrokenPipeError:
        pass
    # the kernel outlives us; wait for it in a thread so it never stays a zombie
    threading.Thread(target=proc.wait, name="haptable-kernel-reaper", daemon=True).start()
    fd = os.dup(proc.stdout.fileno())
    proc.stdout.close()

    def ended() -> int | None:
        proc.kill()
        return proc.wait()

    return fd, ended


def _start_line(table: Table, fd: int, ended: Callable[[], int | None]) -> str:
    """The kernel's first line on ``fd`` (closed after), within ``START_TIMEOUT_S``;
    ``ended()`` kills it and says its exit status (None: not known here)."""
    deadline = time.monotonic() + START_TIMEOUT_S
    buf = b""
    try:
        while b"\n" not in buf:
            left = deadline - time.monotonic()
            if left <= 0:
                ended()
                return f"error: the outputs process did not start within {START_TIMEOUT_S:g} s"
            r, _, _ = select.select([fd], [], [], left)
            if not r:
                continue
            chunk = os.read(fd, 4096)
            if not chunk:
                code = ended()
                why = "" if code is None else f"exit {code}; "
                return f"error: the outputs process ended at start ({why}see {log_path(table)})"
            buf += chunk
    finally:
        os.close(fd)
    return buf.split(b"\n", 1)[0].decode("utf-8", "replace").strip()


def _parent_of(pid: int) -> int | None:
    """The parent process of ``pid`` (None: no such process, or no /proc)."""
    f = stat_fields(pid)
    return int(f[1]) if f is not None and len(f) > 1 else None


class _Starter:
    """This process's fork server, started at its second kernel (a process that starts
    one kernel pays for no server); ``start`` returns None whenever it cannot serve (the
    caller starts an interpreter instead)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._sock: socket.socket | None = None
        self._proc: subprocess.Popen | None = None
        self._pid = -1  # the process the server belongs to (a fork of it has none)
        self._starts = 0
        self._failed = False

    def start(
        self, blob: bytes, env: dict, log_fd: int
    ) -> tuple[int, Callable[[], int | None]] | None:
        with self._lock:
            if self._pid != os.getpid():  # a forked copy of this process: not its server
                self._sock, self._proc, self._pid, self._starts = None, None, os.getpid(), 0
                self._failed = False
            self._starts += 1
            if self._starts < 2 or self._failed:
                return None
            if self._sock is None and not self._open():
                return None
            r, w = os.pipe()
            try:
                message = {"request": blob, "env": env, "cwd": os.getcwd()}
                send_request(self._sock, message, (w, log_fd))
                pid = int(self._reply())
            except (OSError, ValueError, EOFError):
                os.close(r)
                self._drop()
                return None
            finally:
                os.close(w)

        server = self._proc.pid if self._proc is not None else -1

        def ended() -> None:
            # only the server's child: a kernel that died was reaped there, and its pid
            # may be another process's by now (pids wrap on a busy machine)
            if _parent_of(pid) == server:
                with contextlib.suppress(OSError):
                    os.kill(pid, signal.SIGKILL)

        return r, ended

    def _open(self) -> bool:
        mine, theirs = socket.socketpair()
        try:
            self._proc = subprocess.Popen(
                [sys.executable, "-m", "console.kernel.forkserver", str(theirs.fileno())],
                stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                pass_fds=(theirs.fileno(),),
                start_new_session=True,
            )
        except OSError:
            mine.close()
            self._failed = True
            return False
        finally:
            theirs.close()
        self._sock = mine
        threading.Thread(target=self._proc.wait, name="haptable-forkserver", daemon=True).start()
        try:
            ok = self._reply()
        except (OSError, EOFError):
            ok = ""
        if ok != "ok":
            self._drop()
            return False
        return True

    def _reply(self) -> str:
        """One line from the server, within ``START_TIMEOUT_S``."""
        sock = self._sock
        sock.settimeout(START_TIMEOUT_S)
        buf = b""
        while not buf.endswith(b"\n"):
            chunk = sock.recv(1)
            if not chunk:
                raise EOFError
            buf += chunk
        return buf.decode("ascii", "replace").strip()

    def _drop(self) -> None:
        """The server failed: closed, and not asked again in this process."""
        self._failed = True
        if self._sock is not None:
            self._sock.close()
        if self._proc is not None:
            with contextlib.suppress(OSError):
                self._proc.kill()
        self._sock = self._proc = None


_STARTER = _Starter()


def command_line() -> str:
    """This process's command as a user would recognise it (``haptable demo knob``)."""
    import shlex
    from pathlib import Path

    argv = list(getattr(sys, "orig_argv", sys.argv))
    if "-m" in argv[:-1]:
        i = argv.index("-m")
        mod, rest = argv[i + 1], argv[i + 2 :]
        words = (
            ["haptable", *rest]
            if mod in ("console.cli.main", "console.cli.entry")
            else ["python", "-m", mod, *rest]
        )
    else:
        words = [Path(sys.argv[0]).name or "python", *sys.argv[1:]]
    return shlex.join(words)[:200]
