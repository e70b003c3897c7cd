"""Keep the console's memory in RAM while outputs play in real time (``mlockall``).

The kernel's reclaim pages out memory a process has not touched for a while (code of
loaded libraries included); the audio thread touching such a page waits for it to come
back. On the 2-core VM the benchmarks ran on, a real-time thread in a process with the
console's plugins loaded stalled for more than two audio blocks about twice a second
(up to 70 ms) without the lock and once in 30 s with it (``haptable bench soak`` reports
the lock's state). JACK and other real-time audio programs lock their memory for the
same reason.

Locked "on fault" (``MCL_ONFAULT``): pages are pinned as they are first used, so thread
stacks and rings are not filled in up front. Locking needs ``CAP_IPC_LOCK`` (root) or an
unlimited ``memlock`` limit; with a finite limit future allocations beyond it would fail,
so the console does not lock then and says how to allow it.
"""

from __future__ import annotations

import ctypes
import os
import sys
import threading

MCL_CURRENT, MCL_FUTURE, MCL_ONFAULT = 1, 2, 4
CAP_IPC_LOCK = 14
_lock = threading.Lock()
_holders = 0  # open outputs that asked for the lock (the last to close releases it)
HOW_TO_ALLOW = (
    "allow it with a memlock limit of unlimited for the console's user "
    "(/etc/security/limits.d/audio.conf: '@audio - memlock unlimited', user in group audio)"
)


def _may_lock() -> tuple[bool, str]:
    """Whether locking all memory is allowed without risking failed allocations."""
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            caps = next((ln for ln in f if ln.startswith("CapEff:")), "CapEff: 0")
        if int(caps.split()[1], 16) >> CAP_IPC_LOCK & 1:
            return True, "CAP_IPC_LOCK"
    except (OSError, ValueError):
        pass
    import resource

    soft, _ = resource.getrlimit(resource.RLIMIT_MEMLOCK)
    if soft == resource.RLIM_INFINITY:
        return True, "memlock unlimited"
    return False, f"memlock limit {soft // 1024} kB"


def lock_memory() -> tuple[bool, str]:
    """Lock the process's memory (current and future pages, on fault); each successful
    call is matched by one ``unlock_memory``.

    Returns ``(locked, note)``: the note says why not when it is not locked."""
    global _holders
    if not sys.platform.startswith("linux"):
        return False, "memory not locked: mlockall is used on Linux only"
    ok, why = _may_lock()
    if not ok:
        return False, f"memory not locked ({why}): {HOW_TO_ALLOW}"
    with _lock:
        libc = ctypes.CDLL(None, use_errno=True)
        if libc.mlockall(MCL_CURRENT | MCL_FUTURE | MCL_ONFAULT) == 0:
            note = f"memory locked on fault ({why})"
        else:
            err = ctypes.get_errno()
            if libc.mlockall(MCL_CURRENT) != 0:
                return False, f"memory not locked: mlockall failed ({os.strerror(err)})"
            note = f"memory locked (current pages only: {os.strerror(err)})"  # kernel < 4.4
        _holders += 1
        return True, note


def unlock_memory() -> None:
    """Release one lock; the memory is unlocked when no open outputs hold it."""
    global _holders
    with _lock:
        _holders = max(0, _holders - 1)
        if _holders == 0 and sys.platform.startswith("linux"):
            ctypes.CDLL(None, use_errno=True).munlockall()
