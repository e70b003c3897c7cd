"""How late a real-time thread on this machine wakes, measured in a process of its own.

An audio thread has ``buffer_periods - 1`` blocks of slack: when the system keeps it off
the CPU longer than that, the device buffer runs dry whatever the console does. This
probe, run beside a benchmark (``haptable bench soak``), wakes a FIFO-priority thread
every audio block in a fresh, small process with its memory locked and counts the wakes
later than one block and later than the slack. Underruns the console sees at a rate
near the probe's stalls come from the machine (virtual CPU scheduling, the host), not
from the console.

``python -m console.runtime.jitter SECONDS PERIOD_MS SLACK_MS`` prints the result as JSON.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time

from console.kernel.memory_lock import lock_memory


def probe(
    seconds: float, period_s: float, slack_s: float, stop: threading.Event | None = None
) -> dict:
    """Wake every ``period_s`` for ``seconds`` (or until ``stop``) on a real-time thread;
    lateness stats."""
    locked, _ = lock_memory()
    late: list[float] = []
    rt: list[bool] = []

    def run() -> None:
        try:
            prio = os.sched_get_priority_min(os.SCHED_FIFO) + 10
            os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(prio))
            rt.append(True)
        except (AttributeError, OSError):
            rt.append(False)
        end = time.monotonic() + seconds
        due = time.monotonic()
        while due < end and not (stop is not None and stop.is_set()):
            due += period_s
            w = due - time.monotonic()
            if w > 0:
                time.sleep(w)
            late.append(time.monotonic() - due)

    t = threading.Thread(target=run, name="jitter-probe")
    t.start()
    t.join()
    srt = sorted(late)
    n = len(srt)

    def q(p: float) -> float:
        return round(1e3 * srt[min(n - 1, int(p * n))], 3) if n else 0.0

    return {
        "wakes": n,
        "period_ms": round(period_s * 1e3, 3),
        "slack_ms": round(slack_s * 1e3, 3),
        "realtime_priority": bool(rt and rt[0]),
        "memory_locked": locked,
        "late_p50_ms": q(0.5),
        "late_p99_ms": q(0.99),
        "late_p999_ms": q(0.999),
        "late_max_ms": round(1e3 * srt[-1], 3) if n else 0.0,
        "late_over_one_period": sum(x > period_s for x in srt),
        "late_over_slack": sum(x > slack_s for x in srt),
        # wakes later than k periods: what a buffer of k + 1 periods would not have covered
        "late_over_periods": {k: sum(x > k * period_s for x in srt) for k in (1, 2, 3, 4, 6, 8)},
    }


def start_probe(seconds: float, period_s: float, slack_s: float) -> subprocess.Popen:
    """The probe in a child process (read its JSON with ``finish_probe``)."""
    return subprocess.Popen(
        [
            sys.executable,
            "-m",
            "console.runtime.jitter",
            str(seconds),
            str(period_s * 1e3),
            str(slack_s * 1e3),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def start_probe_beside(audio_status: dict, seconds: float) -> subprocess.Popen:
    """The probe for ``seconds`` at the period and slack of the running audio output
    (its ``status()``: block size, sample rate, buffer periods)."""
    period_s = float(audio_status["block_size"]) / float(audio_status["sample_rate_hz"])
    periods = int(audio_status.get("buffer_periods") or 2)
    return start_probe(seconds, period_s, max(1, periods - 1) * period_s)


def finish_probe(proc: subprocess.Popen, timeout_s: float = 60.0, *, now: bool = False) -> dict:
    """The probe's JSON; ``now``: stop it first (it reports the wakes so far)."""
    if now and proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
    try:
        out, err = proc.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        proc.kill()
        return {"error": "the jitter probe did not finish"}
    if proc.returncode != 0:
        return {"error": (err.strip().splitlines() or ["no output"])[-1]}
    return json.loads(out)


if __name__ == "__main__":
    secs, period_ms, slack_ms = (float(x) for x in sys.argv[1:4])
    stopped = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stopped.set())
    print(json.dumps(probe(secs, period_ms / 1e3, slack_ms / 1e3, stopped)))
