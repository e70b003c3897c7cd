"""The relay guard: the kernel's watcher that opens every relay when the kernel dies.

A relay board keeps its contacts as last commanded: a kernel killed with ``kill -9`` (or
by the OOM killer, or a crash below Python) with a relay closed would leave an
amplifier's output wired to the glass until the next kernel starts. The guard is a small
child of the kernel (``python -m console.kernel.relay_guard``), started before the
kernel serves its first client, in a session of its own (a signal to the kernel's
process group does not reach it). It reads the kernel's start request (the profile, the
table, the plugin modules) on stdin and then waits on that pipe:

- ``clean`` from the kernel (it opened every relay itself while closing): it ends;
- the pipe's end without it (the kernel died): it opens the board the profile names,
  opens every relay, closes the board and latches the table's e-stop, so nothing plays
  until an operator has looked.

It holds no device while it waits: the board is the kernel's until the kernel is gone.
A twin board lives in the kernel's memory and dies with it: the kernel starts no guard
for it.
"""

from __future__ import annotations

import contextlib
import os
import pickle
import subprocess
import sys
import time

#: what the kernel writes when it closed its outputs itself
CLEAN = b"clean\n"
#: how long the guard tries to open the board after the kernel died (the kernel's
#: handle on the USB device goes when the kernel is reaped)
OPEN_TRIES_S = 5.0


class Guard:
    """The kernel's end of the guard: ``release()`` once the kernel opened every relay."""

    def __init__(self, request_blob: bytes) -> None:
        self._proc = subprocess.Popen(
            [sys.executable, "-m", __name__, str(os.getpid())],
            stdin=subprocess.PIPE,
            start_new_session=True,
        )
        self._proc.stdin.write(f"{len(request_blob)}\n".encode() + request_blob)
        self._proc.stdin.flush()

    @property
    def pid(self) -> int:
        return self._proc.pid

    def release(self) -> None:
        """The kernel closed its outputs (every relay open): the guard ends."""
        with contextlib.suppress(OSError, ValueError):
            self._proc.stdin.write(CLEAN)
            self._proc.stdin.close()
        with contextlib.suppress(subprocess.TimeoutExpired):
            self._proc.wait(3.0)


def open_every_relay(request: dict) -> str:
    """Build the profile's relay board and open every relay; what was done, in words."""
    # lazy: plugins load only when the kernel died
    from console.config.plugins import import_extra, load_plugins

    pm = load_plugins(extra=import_extra(request.get("extra_plugins") or ()))
    profile = request["profile"]
    name = pm.get("relay_board", profile.get("relays.driver")).name
    t_end = time.monotonic() + OPEN_TRIES_S
    while True:
        try:
            board = pm.build("relay_board", name, profile)
            break
        except Exception as exc:  # noqa: BLE001 - busy until the dead kernel is reaped
            if time.monotonic() > t_end:
                return f"its relay guard could not open the relay board {name!r}: {exc}"
            time.sleep(0.1)
    failed = []
    for ch in range(1, int(board.channels) + 1):
        try:
            board.set(ch, False)
        except Exception:  # noqa: BLE001 - open the others whatever one says
            failed.append(ch)
    with contextlib.suppress(Exception):
        board.close()
    if failed:
        return f"its relay guard opened every relay but {', '.join(map(str, failed))}"
    return "its relay guard opened every relay"


def main() -> int:
    raw = sys.stdin.buffer
    head = raw.readline()
    if not head.strip():
        return 0
    request = pickle.loads(raw.read(int(head)))
    kernel_pid = int(sys.argv[1]) if len(sys.argv) > 1 else os.getppid()
    if raw.read() == CLEAN:  # blocks until the kernel writes it or its end closes the pipe
        return 0
    # lazy: nothing but the pipe while the kernel lives
    from console.kernel.tables import latch_record, table_at, write_latch

    done = open_every_relay(request)
    why = f"the outputs process of this table (pid {kernel_pid}) ended without closing its outputs; {done}"
    write_latch(table_at(request["table_dir"]), latch_record(why, "relay guard"))
    print(f"haptable relay guard: {why}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
