"""A command interrupted while it starts the table's outputs process (ctrl+c in the
first second of the first `haptable play`, its reader of "ready" gone) latched the
table's e-stop: the kernel's "ready" met a broken pipe, an unhandled exception, and
every later command was refused until an operator's reset. The kernel serves the
table all the same: nothing latched, the next command plays."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import time

from console.config.profile import load_profile
from console.kernel.tables import table_for

from .test_kernel import haptable


def test_a_starter_gone_before_ready_latches_nothing(plugins):
    profile = load_profile("sim", plugins)
    table = table_for(profile.path)
    table.ensure()
    blob = pickle.dumps(
        {"table_dir": str(table.dir), "profile": profile, "fast": False, "owner": None}
    )
    proc = subprocess.Popen(
        [sys.executable, "-m", "console.kernel"],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
        env=dict(os.environ),
    )
    proc.stdout.close()  # the starter is gone before the kernel says "ready"
    proc.stdin.write(f"{len(blob)}\n".encode() + blob)
    proc.stdin.close()
    t_end = time.monotonic() + 60
    while not table.control_sock.exists() and time.monotonic() < t_end:
        assert proc.poll() is None, "the kernel ended"
        time.sleep(0.05)
    time.sleep(0.5)  # past its "ready"
    assert not table.latch_path.exists(), table.latch_path.read_text()
    got = haptable("play", "sine-PA")
    assert got.returncode == 0, got.stderr
    proc.terminate()
    proc.wait(30)
