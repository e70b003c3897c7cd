"""Issue 27, new-user try (UI A) 16: quitting while a demo plays does not wait for the
playing plan to end: the console asks the demo to stop ``now`` and its process has the
kernel ramp the plan down (within the slew limit, never cut) before it leaves."""

from __future__ import annotations

import time
from types import SimpleNamespace

import numpy as np

from console.core.types import OutputPlan, Segment
from console.runtime.demo_host import Host
from console.safety import Limits
from console.signals.waveforms import tone

FS = 48000
PLAN_S = 30.0


def test_a_stop_now_ramps_the_playing_plan_down(outputs, profile):
    x = tone(250, 20.0, PLAN_S, FS, 0.01)
    report = outputs.play(OutputPlan(FS, (Segment(x, 0 * x, frozenset({"PA"})),)), wait=False)
    t_end = time.monotonic() + 10
    while report.t_first_sample_s is None and time.monotonic() < t_end:
        time.sleep(0.005)
    sent = []
    host = Host({"demo": "knob"}, SimpleNamespace(send=lambda *a: sent.append(a)))
    host.outputs = outputs
    host.run = SimpleNamespace(stop=lambda: None, snapshot=dict)
    host.command({"cmd": "stop", "now": True})  # as the console sends it at quit
    assert host.stop_asked.is_set() and host.stop_now
    assert host.finish() == 0 and sent[-1][0] == "stopped"
    assert not outputs.status()["busy"], "silent when the demo leaves"
    rec = outputs.recording(as_played=True)[:, 0]
    loud = np.flatnonzero(rec)
    assert loud.size and loud[-1] - loud[0] < 0.5 * PLAN_S * FS, "not played to its end"
    step = Limits.from_profile(profile).column_steps_v(frozenset({"PA"}))[0]
    assert np.abs(np.diff(rec)).max() <= step * 1.0005, "ramped down, never cut"


def test_a_plain_stop_lets_the_plan_end():
    host = Host({"demo": "knob"}, SimpleNamespace(send=lambda *a: None))
    host.command({"cmd": "stop"})
    assert host.stop_asked.is_set() and not host.stop_now
