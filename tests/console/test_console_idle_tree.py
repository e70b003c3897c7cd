"""``bench console-idle`` counts the console's whole CPU: its process and the processes
it started for itself (the twin camera rendering apart), not the table's kernel (a
session of its own, every client's)."""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

from console.benchmarks.console_idle import process_tree, sample

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="/proc")

BURN = "import time\nt = time.monotonic()\nwhile time.monotonic() - t < 30: pass\n"
PARENT = f"""
import subprocess, sys, time
own = subprocess.Popen([sys.executable, "-c", {BURN!r}])
apart = subprocess.Popen([sys.executable, "-c", {BURN!r}], start_new_session=True)
print(own.pid, apart.pid, flush=True)
time.sleep(30)
"""


def test_the_sum_counts_the_children_but_not_a_session_of_their_own():
    own = apart = 0
    parent = subprocess.Popen([sys.executable, "-c", PARENT], stdout=subprocess.PIPE, text=True)
    try:
        own, apart = map(int, parent.stdout.readline().split())
        mine, other = process_tree(parent.pid)
        assert parent.pid in mine and own in mine and apart not in mine
        assert apart in other
        time.sleep(0.5)
        got = sample(parent.pid, 2.0)
        # the parent sleeps: what it costs is its busy child's (a core, less under load:
        # 6 % at load 7.4 on 2 cores; the parent alone reads 0.0), the session leader's
        # is beside it
        assert got["median_pct"] > 2.0, got
        assert any(k.startswith(f"{own} ") for k in got["processes_pct"])
        assert not any(k.startswith(f"{apart} ") for k in got["processes_pct"])
        assert got["kernel_pct"] > 10.0, got
        # the process alone: the sleeping parent's own seconds, not its child's
        assert got["console_cpu_s_per_10s"] < 0.5, got
        assert len(got["load_avg_1min"]) == 2
    finally:
        for pid in (p for p in (own, apart) if p):
            subprocess.run(["kill", str(pid)], check=False)
        parent.kill()
        parent.wait(5)
