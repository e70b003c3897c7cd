"""A flow plan that is not ready is computed beside the frame loop, never inside it (a
plan can take a few 100 ms: inside the loop it would trip the watchdog)."""

from __future__ import annotations

import threading
import time
from types import SimpleNamespace

import numpy as np

from console.core.types import OutputPlan, Segment
from console.signals.waveforms import tone

FS = 48000


class SlowPairs:
    """Two-point flows whose plan blocks until the test releases it."""

    def __init__(self) -> None:
        self.release = threading.Event()
        self.asked: list = []
        sig = tone(250, 10, 0.05, FS, 0.01)
        self.plan_out = OutputPlan(FS, (Segment(sig, np.zeros_like(sig), frozenset({"PA"})),))

    def cached(self, a, b):
        return None

    def plan(self, a, b):
        self.asked.append((a, b))
        self.release.wait(30)
        return self.plan_out


class FakeOutputs:
    def __init__(self) -> None:
        self.played: list = []

    def play(self, plan, wait=False):
        self.played.append(plan)
        return SimpleNamespace(done=threading.Event())


def test_two_finger_flow_is_planned_off_the_frame_loop(profile, plugins):
    from plugins.demos.flow import FlowDemo

    pairs, out = SlowPairs(), FakeOutputs()
    demo = FlowDemo(profile, plugins, out, plans=None, prepare=False, pair_plans=pairs)
    demo.start()
    fingers = [SimpleNamespace(pos_mm=(200.0, 200.0)), SimpleNamespace(pos_mm=(400.0, 200.0))]
    results = []
    for k in range(40):  # two resting fingers for 0.67 s at 60 fps
        frame = SimpleNamespace(t_capture_s=k / 60, seq=k, stamps_s={"arrival": k / 60})
        work = {"contacts": fingers, "hands": ()}
        results.append(demo.effect_stage(frame, work))
    t_end = time.monotonic() + 10  # the planner thread asks (late on a loaded machine)
    while not pairs.asked and time.monotonic() < t_end:
        time.sleep(0.01)
    assert pairs.asked, "the resting pair asked for a plan"
    assert not any(results) and out.played == []  # the loop went on while it was computed
    pairs.release.set()
    t_end = time.monotonic() + 10
    while not out.played and time.monotonic() < t_end:
        time.sleep(0.01)
    demo.stop()
    assert out.played == [pairs.plan_out]
    ev = demo.events[-1]
    assert ev["kind"] == "two_point" and ev["from_mm"][0] < ev["to_mm"][0]
    assert len(pairs.asked) == 1  # once per placement, not once per frame
