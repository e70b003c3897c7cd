"""Issue 27, third new-user try: `haptable signals play` stopped by `haptable estop` from
another shell exits 4 (README: the e-stop's exit status), as `haptable play` does, not 2
(bad input). On a loaded machine the kernel's "stopped" end of the play reaches the
command before the e-stop's own event: the command must still know it was the e-stop."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from console.kernel.tables import table_for

ROOT = Path(__file__).resolve().parents[2]
#: README, Commands: the exit status of a command stopped by `haptable estop`
EXIT_ESTOPPED = 4
LONG = "sine(100 Hz, 5 V, 8 s) * ramp(10 ms)"
#: the command's code with the e-stop's event handled a second late (a loaded machine:
#: the kernel sends the play's end and the e-stop's event from two threads)
LATE_EVENTS = """
import sys, threading
from console.kernel import client

on_gate = client.Outputs._on_gate

def late(self, h):
    if h.get("kind") != "estop":
        return on_gate(self, h)
    threading.Timer(1.0, on_gate, (self, h)).start()

client.Outputs._on_gate = late
from console.cli.main import main
sys.exit(main(sys.argv[1:]))
"""


def _env() -> dict[str, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("HAPTABLE_TWIN_LOG", None)
    return env


def _using(table, pid: int) -> bool:
    """The command of ``pid`` is a client of the table's kernel."""
    import json

    from console.kernel.line_server import request

    try:
        st = json.loads(request(table.control_sock, "status", timeout_s=2.0)[0])
    except (OSError, ValueError):
        return False
    return any(f"(pid {pid})" in c for c in st.get("clients", []))


def test_signals_play_stopped_by_haptable_estop_exits_4():
    import time

    env = _env()
    args = ["signals", "play", LONG, "--patch", "PA"]
    cmd = [sys.executable, "-c", LATE_EVENTS, *args]
    proc = subprocess.Popen(cmd, cwd=ROOT, env=env, stderr=subprocess.PIPE, text=True)
    try:
        table = table_for(ROOT / "profiles" / "sim.toml")
        t_end = time.monotonic() + 30
        while not _using(table, proc.pid):
            assert proc.poll() is None, proc.stderr.read()
            assert time.monotonic() < t_end, "the play never started"
            time.sleep(0.05)
        time.sleep(1.0)  # its plan plays (8 s)
        stop = subprocess.run(
            [sys.executable, "-m", "console.cli.entry", "estop"],
            cwd=ROOT,
            env=env,
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert stop.returncode == 0, stop.stderr
        code = proc.wait(30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    err = proc.stderr.read()
    assert code == EXIT_ESTOPPED, err
    assert "e-stopped by haptable estop" in err, err
