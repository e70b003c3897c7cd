"""Who may reset an e-stop: an operator, never a program.

The kernel asks the peer's credentials (``SO_PEERCRED``) and accepts a reset from:

- the table's console: the process holding the table's ``console.lock`` (a person at the
  console pressed its reset key; one console per table and user);
- `haptable reset` typed at a terminal: the peer runs the ``reset`` command in the
  foreground process group of its controlling terminal (a background job, a pipe, a cron
  job, a process a demo started, or another command of a program has none);
- on a private twin table (tests, benches), the process that started it.

Anything else is told in one line who may reset. This draws the line between processes:
code inside the console's own process can press its keys too. Linux only (``/proc``);
elsewhere only the console and a private table's owner may reset. Standard library only.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from pathlib import Path

#: what a refused program is told
WHO_MAY_RESET = (
    "only an operator resets an e-stop: ctrl+r in the console, or `haptable reset` typed "
    "at a terminal"
)


def stat_fields(pid: int) -> list[str] | None:
    """``/proc/<pid>/stat`` after the command name: state, ppid, pgrp, session, tty_nr,
    tpgid, ... (None: no such process or no /proc)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as f:
            return f.read().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None


def at_terminal(pid: int) -> bool:
    """Whether process ``pid`` runs in the foreground of a controlling terminal."""
    f = stat_fields(pid)
    if f is None or len(f) < 6:
        return False
    try:
        pgrp, tty_nr, tpgid = int(f[2]), int(f[4]), int(f[5])
    except ValueError:
        return False
    return tty_nr != 0 and tpgid > 0 and tpgid == pgrp


def runs_reset(pid: int) -> bool:
    """Whether process ``pid``'s command line is a ``reset`` command."""
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            argv = f.read(4096).split(b"\0")
    except OSError:
        return False
    return b"reset" in argv[1:]


def console_holder(lock_path: Path) -> int | None:
    """The pid of the process holding the table's console lock (None: no console)."""
    try:
        fd = os.open(lock_path, os.O_RDONLY | os.O_NOFOLLOW)
    except OSError:
        return None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:  # held: by the pid written in it
            with contextlib.suppress(OSError, ValueError):
                return int(os.read(fd, 32).decode("ascii", "replace").strip() or "0") or None
            return None
        fcntl.flock(fd, fcntl.LOCK_UN)  # nobody holds it: no console runs
        return None
    finally:
        os.close(fd)


def reset_refusal(
    peer_pid: int, *, console_lock: Path, owner_pid: int | None, via_terminal: bool
) -> str | None:
    """Why ``peer_pid`` may not reset this table's e-stop (None: it may).
    ``via_terminal``: the request came as `haptable reset` (the control socket);
    ``owner_pid``: a private table's owner."""
    if owner_pid is not None and peer_pid == owner_pid:
        return None
    if peer_pid > 0 and console_holder(console_lock) == peer_pid:
        return None
    if via_terminal and peer_pid > 0 and runs_reset(peer_pid) and at_terminal(peer_pid):
        return None
    return f"refused: {WHO_MAY_RESET}"
