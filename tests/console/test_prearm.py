"""Pre-armed relays: a plan's first relays closed ahead, in silence, through the gate."""

from __future__ import annotations

import time

import numpy as np
import pytest

from console.benchmarks.safety import fresh_window
from console.errors import SafetyRefusal
from console.runtime.outputs import open_outputs
from console.safety_audit import received_problems
from console.signals import ramp_envelope
from console.types import OutputPlan, Segment

FS = 48000


def flow_like(patches=frozenset({"PA"}), n: int = 2400, amp_v: float = 40.0) -> OutputPlan:
    env = ramp_envelope(n, round(6e-3 * FS))
    x = amp_v * np.sin(2 * np.pi * 250 * np.arange(n) / FS) * env
    return OutputPlan(FS, (Segment(x, np.zeros(n), frozenset(patches)),), name="flow")


def wait_armed(out, relays: frozenset[int], timeout_s: float = 5.0) -> None:
    t = time.monotonic() + timeout_s
    while out.scheduler.busy or out.gate.relay_state() != relays or not out.gate.settled():
        assert time.monotonic() < t, "pre-arm did not finish"
        time.sleep(0.001)


def problems(out, start, route) -> list[str]:
    return received_problems(
        out.limits,
        out.recording(),
        out.relay_log(),
        list(out.gate.events),
        start,
        frozenset(route),
        int(out.gate.latency_samples),
    )


@pytest.fixture
def paced(profile, plugins):
    """The sim profile's outputs at the sound card's own pace (timing as on a table)."""
    out = open_outputs(profile, plugins, fast=False)
    yield out
    out.close()


def test_prearmed_plan_plays_at_the_next_block_and_the_audit_finds_no_switch_under_signal(
    paced,
):
    out = paced
    block = int(out.gate.latency_samples)
    start = fresh_window(out)
    plan = flow_like({"PA", "PC"})
    out.precheck(plan)
    relays = out.scheduler.relays_for(frozenset({"PA", "PC"}), False)
    assert out.prearm(frozenset({"PA", "PC"}), False) is not None
    wait_armed(out, relays)
    assert not out.recording()[start.rec0 :].any()  # the pre-arm is silent
    waits = []
    for _ in range(3):
        c0 = out.gate.clock
        report = out.play(plan, wait=False)
        report.wait(5)
        assert not report.error
        waits.append(report.segment_start[0] - c0)
        # the plan opened its relays when it ended; arm again for the next one
        assert out.gate.relay_state() == frozenset()
        out.prearm(frozenset({"PA", "PC"}), False)
        wait_armed(out, relays)
    # the first sample is in the first block pulled after the plan was queued
    assert max(waits) <= block, waits
    # without the pre-arm the same plan waits for the guard gap and the relays to settle
    out.disarm()
    wait_armed(out, frozenset())
    c0 = out.gate.clock
    report = out.play(plan, wait=False).wait(5)
    assert report.segment_start[0] - c0 >= out.limits.settle_samples
    log = out.relay_log()[start.log0 :]
    assert log and all(r.level_v == (0.0, 0.0) for r in log)
    assert not problems(out, start, {"PA", "PC"}), problems(out, start, {"PA", "PC"})


def test_a_newer_prearm_or_the_hand_leaving_opens_the_relays_again_in_silence(outputs):
    start = fresh_window(outputs)
    sch = outputs.scheduler
    outputs.prearm(frozenset({"PA"}), False)
    wait_armed(outputs, sch.relays_for(frozenset({"PA"}), False))
    outputs.prearm(frozenset({"PD"}), True)  # another plan was chosen
    wait_armed(outputs, sch.relays_for(frozenset({"PD"}), True))
    assert outputs.disarm() is not None  # the hand left
    wait_armed(outputs, frozenset())
    assert outputs.disarm() is None  # nothing left to undo
    assert outputs.gate.closed_patches() == frozenset()
    assert not outputs.recording()[start.rec0 :].any()
    assert not problems(outputs, start, set())


def test_prearm_is_left_to_a_plan_already_queued(outputs):
    fresh_window(outputs)
    report = outputs.play(flow_like({"PB"}, n=48000), wait=False)
    assert outputs.prearm(frozenset({"PA"}), False) is None  # a plan is queued: no pre-arm
    assert outputs.disarm() is None  # its own end opens the relays
    report.wait(10)
    assert outputs.gate.relay_state() == frozenset()


def test_estop_during_a_prearm_opens_every_relay_and_refuses_more(outputs):
    fresh_window(outputs)
    sch = outputs.scheduler
    relays = sch.relays_for(frozenset({"PA", "PB", "PC", "PD"}), True)
    report = outputs.prearm(frozenset({"PA", "PB", "PC", "PD"}), True)
    # e-stop while it waits for the guard gap or switches, and once it is armed
    outputs.estop("test during pre-arm")
    report.wait(5)
    assert outputs.gate.wait_safe(5)
    assert outputs.gate.relay_state() == frozenset()
    assert report.error.startswith("stopped")
    assert outputs.prearm(frozenset({"PA"}), False) is None  # none during an e-stop
    outputs.reset()
    outputs.prearm(frozenset({"PA", "PB", "PC", "PD"}), True)
    wait_armed(outputs, relays)
    outputs.estop("test when armed")
    assert outputs.gate.wait_safe(5)
    assert outputs.gate.relay_state() == frozenset()
    assert not sch.busy
    with pytest.raises(SafetyRefusal, match="e-stop"):
        outputs.play(flow_like(), wait=False)


def test_prearm_never_overrides_the_operators_relays(outputs):
    fresh_window(outputs)
    outputs.set_relays({3})
    assert outputs.prearm(frozenset({"PA"}), False) is None
    assert outputs.disarm() is None
    time.sleep(0.05)
    assert outputs.gate.relay_state() == frozenset({3})
    # a plan still routes its own way and gives the operator's setting back
    outputs.play(flow_like({"PA"}))
    assert outputs.gate.relay_state() == frozenset({3})
    outputs.set_relays(set())
    assert outputs.prearm(frozenset({"PA"}), False) is not None
    # an operator command queued behind a pre-arm wins: the pre-arm is not redone over it
    outputs.set_relays({2})
    assert outputs.gate.relay_state() == frozenset({2})
    assert outputs.prearm(frozenset({"PA"}), False) is None
