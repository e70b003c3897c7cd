"""Starting a table's kernel process (``python -m console.kernel``) for a client.

The kernel gets its start request on stdin (the table's folder, the profile, pickled, and
the plugins this process was given beyond the installed ones) and answers one line on
stdout: ``ready``, ``busy: ...`` (another client started it meanwhile) or ``error: ...``
(its one-line reason). It runs in a session of its own (its terminal's signals are not an
e-stop), with nothing of the client's inherited but the environment, and outlives it;
its stderr goes to ``kernel.log`` in the table's folder.
"""

from __future__ import annotations

import os
import pickle
import select
import subprocess
import sys
import threading
import time
from typing import Any

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
    started meanwhile) or ``error: ...``."""
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
        proc = subprocess.Popen(
            [sys.executable, "-m", "console.kernel"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=log_fd,
            start_new_session=True,  # its terminal's signals are not an e-stop
            close_fds=True,
            env=env,
        )
    finally:
        os.close(log_fd)
    try:
        proc.stdin.write(f"{len(blob)}\n".encode() + blob)
        proc.stdin.close()
    except BrokenPipeError:
        pass
    deadline = time.monotonic() + START_TIMEOUT_S
    buf = b""
    fd = proc.stdout.fileno()
    while b"\n" not in buf:
        left = deadline - time.monotonic()
        if left <= 0:
            proc.kill()
            return f"error: the outputs process did not start within {START_TIMEOUT_S:g} s"
        r, _, _ = select.select([fd], [], [], left)
        if not r:
            continue
        chunk = os.read(fd, 4096)
        if not chunk:
            code = proc.wait()
            return f"error: the outputs process ended at start (exit {code}; see {log_path(table)})"
        buf += chunk
    proc.stdout.close()
    # the kernel outlives us; wait for it in a thread so it never stays a zombie
    threading.Thread(target=proc.wait, name="haptable-kernel-reaper", daemon=True).start()
    return buf.split(b"\n", 1)[0].decode("utf-8", "replace").strip()


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
