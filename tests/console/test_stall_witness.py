"""Where a late real-time thread's time went: the machine (steal), the scheduler (run-queue
wait), its own work (CPU time) or the process (none of these: a lock, the interpreter)."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import pytest

from console.core.realtime import realtime_priority
from console.core.stall_witness import ORIGINS, StallWitness

SLACK_S = 0.010


def _files(tmp_path: Path, cpu_ns: int, wait_ns: int, steal: int) -> tuple[str, str]:
    sched, stat = tmp_path / "schedstat", tmp_path / "stat"
    sched.write_text(f"{cpu_ns} {wait_ns} 7\n")
    stat.write_text(f"cpu  100 0 50 9000 3 0 1 {steal} 0 0\ncpu0 50 0 25 4500 1 0 0 0 0 0\n")
    return str(sched), str(stat)


@pytest.mark.parametrize(
    ("cpu_ms", "wait_ms", "steal_ticks", "origin"),
    [
        (1, 1, 1, "host"),  # the hypervisor ran something else: whatever the rest says
        (1, 8, 0, "scheduler"),  # runnable, waiting for a CPU
        (9, 0, 0, "compute"),  # it ran: its own work was slow
        (1, 1, 0, "process"),  # neither: a lock, the interpreter, a page fault
    ],
)
def test_each_origin_is_told_from_the_deltas(tmp_path, cpu_ms, wait_ms, steal_ticks, origin):
    sched, stat = _files(tmp_path, 10**9, 5 * 10**8, 40)
    w = StallWitness(sched, stat)
    w.note()
    _files(tmp_path, 10**9 + cpu_ms * 10**6, 5 * 10**8 + wait_ms * 10**6, 40 + steal_ticks)
    assert w.why(SLACK_S) == origin
    w.close()


def test_without_the_files_it_says_unknown(tmp_path):
    w = StallWitness(str(tmp_path / "none"), str(tmp_path / "none2"))
    w.note()
    assert w.why(SLACK_S) == "unknown"
    assert "unknown" in ORIGINS


def _in_thread(work) -> tuple[list[str], bool]:
    """``why`` after ``work`` in a fresh thread at real-time priority where granted, five
    tries (a steal tick may fall in one); and whether the priority was granted."""
    seen: list[str] = []
    granted: list[bool] = []

    def run() -> None:
        granted.append(realtime_priority())
        w = StallWitness()
        for _ in range(5):
            w.note()
            work()
            seen.append(w.why(SLACK_S))
        w.close()

    t = threading.Thread(target=run)
    t.start()
    t.join()
    return seen, granted[0]


@pytest.mark.skipif(not Path("/proc/thread-self/schedstat").exists(), reason="Linux only")
def test_a_thread_that_computed_or_slept_is_told_apart_on_this_machine():
    def busy() -> None:
        t_end = time.thread_time() + 0.03
        while time.thread_time() < t_end:
            pass

    computed, realtime = _in_thread(busy)
    slept, _ = _in_thread(lambda: time.sleep(0.03))
    # running (or runnable, waiting for a CPU) is never taken for waiting in the process
    assert set(computed) <= {"compute", "host", "scheduler"}, computed
    assert "process" in slept and set(slept) <= {"process", "host", "scheduler"}, slept
    if realtime:  # nothing of normal priority takes its CPU: its own work was the time
        assert "compute" in computed, computed
