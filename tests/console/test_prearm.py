"""Pre-armed relays: a plan's first relays closed ahead, in silence, through the gate."""

from __future__ import annotations

import time

import numpy as np
import pytest

from console.benchmarks.safety import fresh_window
from console.core.errors import SafetyRefusal
from console.core.types import OutputPlan, Segment
from console.kernel.table import TableOutputs
from console.safety.audit import Window, received_problems
from console.signals.waveforms import ramp_envelope

FS = 48000


def flow_like(patches=frozenset({"PA"}), n: int = 2400, amp_v: float = 40.0) -> OutputPlan:
    env = ramp_envelope(n, round(6e-3 * FS))
    x = amp_v * np.sin(2 * np.pi * 250 * np.arange(n) / FS) * env
    return OutputPlan(FS, (Segment(x, np.zeros(n), frozenset(patches)),), name="flow")


def relays_for(out, patches, screen: bool) -> frozenset[int]:
    """The relays a plan on ``patches`` (and the screen) closes, from the profile."""
    prof = out.profile
    chans = {
        int(p["relay_channel"])
        for name, p in prof.items("patches").items()
        if name in patches and p.get("relay_channel")
    }
    if screen:
        chans.add(int(prof.get("screen.relay_channel")))
    return frozenset(chans)


def wait_armed(out, relays: frozenset[int], timeout_s: float = 5.0) -> None:
    """Until the kernel has nothing queued and ``relays`` are closed (a pre-arm's job
    ends only once its relays have settled)."""
    t = time.monotonic() + timeout_s
    while out.status()["busy"] or out.relay_state() != relays:
        assert time.monotonic() < t, "pre-arm did not finish"
        time.sleep(0.001)


def wait_armed_here(table, relays: frozenset[int], timeout_s: float = 5.0) -> None:
    """``wait_armed`` on the table's core in this process."""
    gate = table.gate
    t = time.monotonic() + timeout_s
    while table.scheduler.busy or gate.relay_state() != relays or not gate.settled():
        assert time.monotonic() < t, "pre-arm did not finish"
        time.sleep(0.001)


def problems(out, start, route) -> list[str]:
    return received_problems(
        out.limits,
        out.recording(),
        out.relay_log(),
        out.events(),
        start,
        frozenset(route),
        int(out.status()["latency_samples"]),
    )


@pytest.fixture
def paced(profile, plugins):
    """The sim profile's table core at the sound card's own pace (timing as on a table),
    built in this process: the plan's first sample is compared with the gate's clock when
    the plan was queued, with no socket between them."""
    t = TableOutputs(profile, plugins, fast=False)
    yield t
    t.close()


def test_prearmed_plan_plays_at_the_next_block_and_the_audit_finds_no_switch_under_signal(
    paced,
):
    out = paced
    gate, sch = out.gate, out.scheduler
    block = int(gate.latency_samples)
    start = Window(out.recording().shape[0], len(out.relay_log()), time.monotonic())
    plan = out.check(flow_like({"PA", "PC"}))  # checked ahead, as a client's precheck
    relays = sch.relays_for(frozenset({"PA", "PC"}), False)
    assert relays == relays_for(out, {"PA", "PC"}, False)
    assert sch.prearm(frozenset({"PA", "PC"}), False) is not None
    wait_armed_here(out, relays)
    assert not out.recording()[start.rec0 :].any()  # the pre-arm is silent
    waits = []
    for _ in range(3):
        report = out.play(plan, wait=False)
        queued = gate.clock  # the clock once the plan is queued (a loaded test thread
        report.wait(5)  # may be late to read it before: not the plan's wait)
        assert not report.error
        waits.append(report.segment_start[0] - queued)
        # the plan opened its relays when it ended; arm again for the next one
        assert gate.relay_state() == frozenset()
        sch.prearm(frozenset({"PA", "PC"}), False)
        wait_armed_here(out, relays)
    # the first sample is in the first block pulled after the plan was queued (or one
    # pulled while the clock was read)
    assert max(waits) <= block, waits
    # without the pre-arm the same plan waits for the guard gap and the relays to settle
    sch.disarm()
    wait_armed_here(out, frozenset())
    c0 = gate.clock
    report = out.play(plan, wait=False).wait(5)
    assert report.segment_start[0] - c0 >= out.limits.settle_samples
    log = out.relay_log()[start.log0 :]
    assert log and all(r.level_v == (0.0, 0.0) for r in log)
    found = received_problems(
        out.limits,
        out.recording(),
        out.relay_log(),
        list(gate.events),
        start,
        frozenset({"PA", "PC"}),
        block,
    )
    assert not found, found


def test_a_prearmed_plan_through_the_kernel_plays_without_the_relays_wait(outputs):
    """The same through a kernel client: the pre-arm closes the relays in silence, the
    plan (checked ahead) then plays on them without a switch of its own; its relays open
    when it ends."""
    start = fresh_window(outputs)
    plan = flow_like({"PA", "PC"})
    outputs.precheck(plan)
    relays = relays_for(outputs, {"PA", "PC"}, False)
    assert outputs.prearm(frozenset({"PA", "PC"}), False) is not None
    wait_armed(outputs, relays)
    assert not outputs.recording()[start.rec0 :].any()  # the pre-arm is silent
    n_switches = len(outputs.relay_log())
    report = outputs.play(plan)
    assert not report.error and report.segment_start
    closing = [r for r in outputs.relay_log()[n_switches:] if r.closed]
    assert not closing, "the plan played on the pre-armed relays"
    assert all(r.clock >= report.segment_end[0] for r in outputs.relay_log()[n_switches:])
    assert outputs.relay_state() == frozenset()
    assert not problems(outputs, start, {"PA", "PC"}), problems(outputs, start, {"PA", "PC"})


def test_a_newer_prearm_or_the_hand_leaving_opens_the_relays_again_in_silence(outputs):
    start = fresh_window(outputs)
    outputs.prearm(frozenset({"PA"}), False)
    wait_armed(outputs, relays_for(outputs, {"PA"}, False))
    outputs.prearm(frozenset({"PD"}), True)  # another plan was chosen
    wait_armed(outputs, relays_for(outputs, {"PD"}, True))
    assert outputs.disarm() is not None  # the hand left
    wait_armed(outputs, frozenset())
    assert outputs.disarm() is None  # nothing left to undo
    assert outputs.relay_state() == frozenset()
    assert not outputs.recording()[start.rec0 :].any()
    assert not problems(outputs, start, set())


def test_prearm_is_left_to_a_plan_already_queued(outputs):
    fresh_window(outputs)
    report = outputs.play(flow_like({"PB"}, n=48000), wait=False)
    assert outputs.prearm(frozenset({"PA"}), False) is None  # a plan is queued: no pre-arm
    assert outputs.disarm() is None  # its own end opens the relays
    report.wait(10)
    assert not report.error
    assert outputs.relay_state() == frozenset()
    assert not any(r.channel == 1 for r in outputs.relay_log()), "PA was never armed"


def test_estop_during_a_prearm_opens_every_relay_and_refuses_more(outputs):
    fresh_window(outputs)
    relays = relays_for(outputs, {"PA", "PB", "PC", "PD"}, True)
    report = outputs.prearm(frozenset({"PA", "PB", "PC", "PD"}), True)
    # e-stop while it waits for the guard gap or switches (on a loaded machine it may
    # have armed already before the e-stop reached it: then it ended without an error),
    # and once it is armed
    outputs.estop("test during pre-arm")
    report.wait(5)
    assert outputs.wait_safe(5)
    assert outputs.relay_state() == frozenset()  # every relay open either way
    assert report.error == "" or report.error.startswith("stopped"), report.error
    assert outputs.prearm(frozenset({"PA"}), False) is None  # none during an e-stop
    outputs.reset()
    outputs.prearm(frozenset({"PA", "PB", "PC", "PD"}), True)
    wait_armed(outputs, relays)
    outputs.estop("test when armed")
    assert outputs.wait_safe(5)
    assert outputs.relay_state() == frozenset()
    assert not outputs.status()["busy"]
    with pytest.raises(SafetyRefusal, match="e-stop"):
        outputs.play(flow_like(), wait=False)


def test_prearm_never_overrides_the_operators_relays(outputs):
    fresh_window(outputs)
    outputs.set_relays({3})
    assert outputs.prearm(frozenset({"PA"}), False) is None
    assert outputs.disarm() is None
    time.sleep(0.05)
    assert outputs.relay_state() == frozenset({3})
    # a plan still routes its own way and gives the operator's setting back
    outputs.play(flow_like({"PA"}))
    assert outputs.relay_state() == frozenset({3})
    outputs.set_relays(set())
    assert outputs.prearm(frozenset({"PA"}), False) is not None
    # an operator command queued behind a pre-arm wins: the pre-arm is not redone over it
    outputs.set_relays({2})
    assert outputs.relay_state() == frozenset({2})
    assert outputs.prearm(frozenset({"PA"}), False) is None
