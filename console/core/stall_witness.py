"""Why a real-time thread came back late: the machine, the scheduler or the process.

An audio driver's thread that misses its slack makes an underrun; the count alone does not
say what to fix. The thread keeps a witness: at each cycle it notes its own CPU time and
run-queue wait (``/proc/thread-self/schedstat``, nanoseconds) and the machine's steal time
(``/proc/stat``: time the hypervisor ran something else on this machine's CPUs); when a
cycle is late the deltas since the last note say where the time went:

- ``host``: the machine's steal counter rose (a virtual machine whose CPUs the
  hypervisor did not run: nothing inside the machine could have run the thread);
- ``scheduler``: the thread was runnable but waited for a CPU (another real-time thread,
  the operating system's own work);
- ``compute``: the thread itself ran for most of the slack (its fill was slow);
- ``process``: none of these: it waited inside the process (the interpreter lock held by
  another thread, a lock, a page fault).

On a system without these files (not Linux) every late cycle is ``unknown``. Reading both
costs about 10 microseconds per cycle.
"""

from __future__ import annotations

import contextlib
import os

#: Origins ``why`` returns, in the order they are judged.
ORIGINS = ("host", "scheduler", "compute", "process", "unknown")

_USER_HZ = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100


def _read(fd: int, n: int) -> bytes:
    return os.pread(fd, n, 0)


class StallWitness:
    """Notes of one thread's schedule; create and use it from that thread only."""

    def __init__(
        self, schedstat: str = "/proc/thread-self/schedstat", stat: str = "/proc/stat"
    ) -> None:
        self._sched = self._stat = -1
        with contextlib.suppress(OSError, AttributeError):
            self._sched = os.open(schedstat, os.O_RDONLY)
            self._stat = os.open(stat, os.O_RDONLY)
        self._base: tuple[int, int, float] | None = None

    def _now(self) -> tuple[int, int, float] | None:
        """(CPU ns, run-queue wait ns, machine steal s), or None where unreadable."""
        if self._sched < 0 or self._stat < 0:
            return None
        try:
            cpu, wait = _read(self._sched, 128).split()[:2]
            first = _read(self._stat, 256).split(b"\n", 1)[0].split()
            steal = int(first[8]) / _USER_HZ if len(first) > 8 else 0.0
            return int(cpu), int(wait), steal
        except (OSError, ValueError, IndexError):
            return None

    def note(self) -> None:
        """The start of a cycle: what ``why`` measures from."""
        self._base = self._now()

    def why(self, slack_s: float) -> str:
        """Where the time since the last ``note`` went, as one of ``ORIGINS``."""
        now, base = self._now(), self._base
        if now is None or base is None:
            return "unknown"
        cpu_s = (now[0] - base[0]) * 1e-9
        wait_s = (now[1] - base[1]) * 1e-9
        if now[2] > base[2]:
            return "host"
        if wait_s >= slack_s / 2:
            return "scheduler"
        if cpu_s >= slack_s / 2:
            return "compute"
        return "process"

    def close(self) -> None:
        for fd in (self._sched, self._stat):
            if fd >= 0:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._sched = self._stat = -1
