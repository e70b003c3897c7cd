"""Scenes' `flow right: N played` counts plays only, and says how many of them were
played once their plan was computed off the frame loop (a new operator's try: Scenes
said `1 played` while Latency counted 0 frames whose decision scheduled output; the
count was of every flow event, a refusal or a place without a flow too, and a flow
planned off the loop is scheduled by no frame's decision)."""

from __future__ import annotations

import threading
from types import SimpleNamespace

import numpy as np
import pytest

from console.core.types import OutputPlan, Segment
from console.signals.waveforms import tone

FS = 48000


class FakeOutputs:
    def play(self, plan, wait=False):
        return SimpleNamespace(done=threading.Event())


def test_only_plays_count_and_late_ones_are_said(profile, plugins):
    from plugins.demos.flow import FlowDemo
    from plugins.demos.run import demo_state
    from plugins.demos.status import _flow_text

    demo = FlowDemo(profile, plugins, FakeOutputs(), plans=None, prepare=False)
    sig = tone(250, 10, 0.05, FS, 0.01)
    plan = OutputPlan(FS, (Segment(sig, np.zeros_like(sig), frozenset({"PA"})),))
    frame = SimpleNamespace(seq=1, stamps_s={"arrival": 0.0})
    demo._log_event({"kind": "no_flow", "reason": "no flow here", "seq": 0})
    demo._log_event({"kind": "refused", "reason": "e-stop active", "seq": 0})
    state = demo_state(demo)["flow"]
    assert state["flows"] == 0 and state["flows_late"] == 0, state
    assert "0 played" in _flow_text(state), _flow_text(state)
    demo._play(plan, (100.0, 100.0), "right", (100.0, 100.0), frame, late_s=0.0)
    demo._play(plan, (100.0, 100.0), "right", (100.0, 100.0), frame, late_s=0.3)
    state = demo_state(demo)["flow"]
    assert state["flows"] == 2 and state["flows_late"] == 1, state
    text = _flow_text(state)
    assert "2 played (1 planned outside the frame loop, not in Latency's end to end)" in text
    off = demo_state(demo)["off_loop"]  # Latency's row of them: how many, their planning
    assert off["n"] == 1 and off["planning_ms"]["max_ms"] == pytest.approx(300.0), off
