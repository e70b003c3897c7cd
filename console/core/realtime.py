"""Real-time (FIFO) scheduling for the threads that must not wait for the rest of the
machine: the audio driver's thread (as PortAudio and JACK do) and a demo's frame loop,
a step below it. Where the system does not allow it (no ``rtprio`` limit, no
CAP_SYS_NICE) the thread keeps normal scheduling; callers report which one they got."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator

#: FIFO priorities above the minimum: audio first, then the frame loop, then the threads
#: that serve them (relay switching, the watchdog, a demo's status): a thread of normal
#: priority holding the interpreter while another program runs would make the real-time
#: ones wait for it (the interpreter lock knows no priorities)
HOW_TO_ALLOW = (
    "allow it with a real-time priority limit for the console's user "
    "(/etc/security/limits.d/audio.conf: '@audio - rtprio 95', user in group audio)"
)

AUDIO_PRIORITY = 10
#: the outputs kernel's other threads (serving clients, relays, the latch): a thread that
#: holds the interpreter lock while another program's real-time thread keeps it off the
#: CPU makes the audio thread wait for that lock, so they run above any client's loop
KERNEL_PRIORITY = 8
FRAMES_PRIORITY = 5
SUPPORT_PRIORITY = 1


def realtime_priority(above_min: int = AUDIO_PRIORITY) -> bool:
    """Give the calling thread FIFO scheduling at ``min + above_min``; False where it is
    not permitted (or not on Linux). Processes it starts get normal scheduling."""
    try:
        prio = os.sched_get_priority_min(os.SCHED_FIFO) + above_min
        policy = os.SCHED_FIFO | getattr(os, "SCHED_RESET_ON_FORK", 0)
        os.sched_setscheduler(0, policy, os.sched_param(prio))  # 0: this thread
        return True
    except (AttributeError, OSError):
        return False


@contextlib.contextmanager
def support_priority() -> Iterator[bool]:
    """The calling thread at ``SUPPORT_PRIORITY`` for the block (as a demo's process
    serves its real-time threads: benchmarks that run a demo in their own process), its
    scheduling restored after. Yields whether it was granted."""
    try:
        before = (os.sched_getscheduler(0), os.sched_getparam(0))
    except (AttributeError, OSError):
        yield False
        return
    got = realtime_priority(SUPPORT_PRIORITY)
    try:
        yield got
    finally:
        if got:
            with contextlib.suppress(OSError):
                os.sched_setscheduler(0, *before)


def may_use_realtime() -> bool:
    """Whether a thread of this process gets FIFO scheduling (tried on a throwaway one)."""
    import threading

    got: list[bool] = []
    t = threading.Thread(target=lambda: got.append(realtime_priority(SUPPORT_PRIORITY)))
    t.start()
    t.join()
    return bool(got and got[0])
