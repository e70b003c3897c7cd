"""A demo in its own process (``console.runtime.demo_process`` / ``demo_host``): it runs and
reports, it stops with its outputs silent and open, and whatever ends it (the console
vanishing, a kill, a bad request) ends it safely with one line saying why."""

from __future__ import annotations

import json
import os
import re
import signal
import time
from pathlib import Path

import numpy as np
import pytest

from console.core.errors import UserError
from console.runtime.demo_process import DemoCancelled, DemoProcess


def _relay_log(run) -> list[dict]:
    return json.loads(Path(run.final["twin_log"]).read_text())["relay_log"]


def _wait(cond, timeout_s: float, what: str) -> None:
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        if cond():
            return
        time.sleep(0.05)
    raise AssertionError(f"{what} not reached in {timeout_s:g} s")


def test_a_knob_demo_runs_reports_and_stops_silent(profile, tmp_path):
    steps: list[str] = []
    scene: list[dict] = []  # what the console forwards to the projector
    run = DemoProcess(profile, "knob", on_scene=scene.append, twin_log=tmp_path / "knob.json")
    try:
        run.wait_started(lambda f, text: steps.append(text))
        assert steps and steps[-1].startswith("opening the") and run.running
        assert run.scene_name == "knob" and run.camera is run  # the twin can be touched
        screen = int(profile.get("screen.relay_channel"))

        def turning() -> bool:
            s = run.snapshot()
            seen = s["hand"]["hands"] >= 1  # the scripted hand rests between turns
            return s["knob"]["crossings"] >= 3 and s["latency"]["frames"] >= 60 and seen

        _wait(turning, 30, "the scripted hand turning the knob")
        snap = run.snapshot()
        assert snap["demo"] == "knob" and snap["running"]
        assert snap["hand"]["hands"] >= 1  # what its camera saw
        assert snap["latency"]["end_to_end"]["n"] > 0
        assert snap["outputs"]["gate"]["estopped"] is False
        assert any(e["type"] == "knob" and "angle_deg" in e for e in scene)
    finally:
        run.stop()
    assert run.proc.returncode == 0 and run.exit_reason == "stopped"
    final = run.final["final"]
    assert final["running"] is False
    lines = run.status_lines(run.snapshot())  # the demo plugin's words, here
    assert lines[0].startswith("[b]knob[/b] [yellow]loop stopped")
    # the knob's line: the item under the finger, or none (the scripted hand may have
    # stopped between items or off the knob: a loaded run stopped it there)
    assert any(re.match(r"knob HD\+CF: (item \d+|no item), angle", line) for line in lines), lines
    assert final["outputs"]["gate"]["level_v"] == [0.0, 0.0]
    assert final["outputs"]["gate"]["relays_closed"] == []
    log = _relay_log(run)
    assert any(r["channel"] == screen and r["closed"] for r in log)  # the knob played
    assert not log[-1]["closed"]
    with np.load(tmp_path / "knob.npz") as z:
        assert np.any(z["recording_v"][:, 1])  # friction on the screen electrode


def test_the_console_vanishing_estops_the_demo(profile, tmp_path):
    run = DemoProcess(profile, "knob", twin_log=tmp_path / "knob.json")
    run.wait_started()
    run.proc.stdin.close()  # what the console's death looks like from the demo's side
    assert run.wait_ended(20)
    assert run.proc.returncode == 0
    assert "console closed" in run.estop_reason
    assert run.final["final"]["outputs"]["gate"]["estopped"]
    assert not _relay_log(run)[-1]["closed"]


def test_a_killed_demo_process_is_noticed(profile):
    run = DemoProcess(profile, "knob")
    run.wait_started()
    os.kill(run.proc.pid, signal.SIGKILL)
    assert run.wait_ended(10)
    assert run.stopped and not run.running
    assert "exited (code -9)" in run.exit_reason
    assert run.snapshot()["running"] is False
    run.stop()  # still safe


def test_a_bad_request_is_one_line(profile):
    run = DemoProcess(profile, "knob", params={"condition": "XX"})
    with pytest.raises(UserError) as err:
        run.wait_started()
    assert "XX" in str(err.value) and "\n" not in str(err.value)
    assert run.wait_ended(10) and run.proc.returncode == 2


def test_cancelling_while_it_starts(profile):
    run = DemoProcess(profile, "knob")
    with pytest.raises(DemoCancelled):
        run.wait_started(cancelled=lambda: True)
    assert run.proc.poll() is not None
    assert run.exit_reason == "cancelled"


def test_a_demo_that_does_not_stop_in_time_is_terminated_cleanly(profile, monkeypatch):
    """``stop()`` terminates a host that ignores the stop request (its preparation is slow
    on a loaded machine): the host leaves through its own exit path (no interpreter abort,
    which the command thread's read of stdin would cause) and the run says why it ended."""
    run = DemoProcess(profile, "knob")
    run.wait_started()
    monkeypatch.setattr(run, "_send", lambda msg: True)  # the host never hears "stop"
    run.stop("cancelled", timeout_s=0.5)
    assert run.proc.returncode == 128 + signal.SIGTERM  # not -6 (SIGABRT)
    assert run.exit_reason == "cancelled"
