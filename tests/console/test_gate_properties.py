"""Property tests of the safety gate with injected faults: whatever plans, streams, attached
sources, relay commands and e-stops arrive, the twin's amplifiers and relays only ever see
samples inside the limits and the slew limit, switches in silence, and silence within one
block (plus the ramp down) of an e-stop."""

from __future__ import annotations

import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from console.benchmarks.safety import (
    ROUTES,
    FaultyStream,
    fresh_window,
    plan_case,
    relay_case,
    source_case,
)
from console.safety_audit import Window, received_problems
from console.signals import ramp_envelope
from console.types import OutputPlan, Segment

FS = 48000
BLOCK = 64
PROPS = settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


fresh = fresh_window


def check_received(outputs, start: Window, route: frozenset[str]) -> None:
    problems = received_problems(
        outputs.limits,
        outputs.recording(),
        outputs.relay_log(),
        list(outputs.gate.events),
        start,
        route,
        BLOCK,
    )
    assert not problems, problems


# ------------------------------------------------------------------------- properties
FAULTS = st.sampled_from(["none", "nan", "step", "raise", "object", "stall", "wrong_len"])


def signal(n: int, amp: float, f: float) -> np.ndarray:
    t = np.arange(n) / FS
    return amp * np.sin(2 * np.pi * f * t) * ramp_envelope(n, 480)


@PROPS
@given(
    route=st.sampled_from(sorted(ROUTES)),
    amp=st.floats(0.5, 95),
    f=st.floats(20, 700),
    fault=FAULTS,
    at=st.integers(0, 3000),
    step_at=st.integers(0, 4000),
    step_v=st.floats(0, 200),
    estop_s=st.none() | st.floats(0, 0.02),
)
def test_plans_with_faults(outputs, route, amp, f, fault, at, step_at, step_v, estop_s):
    start = fresh(outputs)
    plan_case(outputs, ROUTES[route], amp, f, fault, at, step_at, step_v, estop_s)
    check_received(outputs, start, ROUTES[route])


@PROPS
@given(
    route=st.sampled_from(sorted(ROUTES)),
    amp=st.floats(0.5, 95),
    f=st.floats(20, 700),
    fault=FAULTS,
    at=st.integers(0, 6000),
    estop_s=st.none() | st.floats(0, 0.02),
    attach=st.booleans(),
)
def test_streams_and_attached_sources_with_faults(
    outputs, route, amp, f, fault, at, estop_s, attach
):
    start = fresh(outputs)
    source_case(outputs, ROUTES[route], amp, f, fault, at, estop_s, attach)
    check_received(outputs, start, ROUTES[route])


@PROPS
@given(
    cmds=st.lists(
        st.tuples(
            st.sampled_from(["set", "play", "estop", "reset", "switch"]),
            st.frozensets(st.integers(1, 8), max_size=3),
        ),
        min_size=1,
        max_size=12,
    )
)
def test_relay_command_sequences(outputs, cmds):
    start = fresh(outputs)
    relay_case(outputs, cmds)
    check_received(outputs, start, frozenset({"PA"}))
    if outputs.gate.estopped:
        assert outputs.gate.relay_state() == frozenset()
    elif not any(kind == "switch" for kind, _ in cmds):  # a direct gate switch is neither
        assert outputs.gate.relay_state() == outputs.scheduler.operator_relays


@pytest.mark.parametrize("fault", ["stall", "raise", "object", "nan"])
def test_the_audio_thread_survives_every_fault(outputs, fault):
    fresh(outputs)
    outputs.stream(FaultyStream(ROUTES["PA"], 10.0, 200.0, fault, 960, 9600)).wait(10)
    assert outputs.gate.estopped
    outputs.gate.wait_safe(5)
    c0 = outputs.gate.clock
    outputs.reset()
    x = signal(2400, 10.0, 250.0)
    outputs.play(OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),)))
    assert outputs.gate.clock > c0


@pytest.mark.parametrize("lands", ["before", "after", "heard_late"])
def test_an_estop_landing_as_a_loud_block_is_handed_over_stays_silent(outputs, lands):
    """An operator's e-stop landing while the gate hands over a loud block it has already
    checked: its event takes the clock of the block's first sample ("before", "heard_late")
    or of its end ("after"), and the driver hears it before it stores the block (drops
    it) or, "heard_late", only after (plays it whole and drops the next). Either way the
    twin must drop the rest of the gate's ramp down too: played after the cut, its first
    sample (the block's last level less one slew step) stepped the amplifiers up from 0 V,
    as the property test above met under load; and the audit must take the cut at the
    block's end ("heard_late") for the cut it is. Here the timing is injected."""
    from console.benchmarks.safety import FaultySource

    gate = outputs.gate
    route = ROUTES["PA"]
    step_v = float(outputs.limits.column_steps_v(route)[0])
    start = fresh(outputs)
    outputs.set_relays({gate.relay_channels["PA"]})
    hand = gate._hand
    landed: list[int] = []  # the clock of the block the e-stop landed on
    deaf: list = []  # the driver's listener, held back while the block is stored

    def hand_with_estop(out, cols):
        if deaf:  # the next block (the gate's ramp down): the driver hears the event now
            ev = [e for e in gate.events if e.kind == "estop"][-1]
            for listener in deaf:
                gate.listeners.append(listener)
                listener(ev)
            deaf.clear()
        if landed or abs(float(cols[0][-1])) <= 2.2 * step_v:  # a ramp down of 3+ samples
            hand(out, cols)
            return
        landed.append(gate.clock)
        if lands == "heard_late":
            deaf.extend(gate.listeners)
            gate.listeners.clear()
        if lands != "after":
            gate.estop("operator", wait=False)
        hand(out, cols)
        if lands == "after":
            gate.estop("operator", wait=False)

    gate._hand = hand_with_estop
    try:
        gate.attach(FaultySource(route, 90.0, 250.0, "none", 10**6, 9600, FS))
        t_end = time.monotonic() + 10
        while not gate.estopped and time.monotonic() < t_end:
            time.sleep(0.001)
        assert gate.wait_safe(5)
    finally:
        gate._hand = hand
    assert landed and not deaf, "the e-stop never landed on a loud block"
    stop = [e for e in gate.events if e.kind == "estop" and e.t_s >= start.t0_s][0]
    assert stop.clock == landed[0] + (BLOCK if lands == "after" else 0)
    check_received(outputs, start, route)
    cut = landed[0] + (BLOCK if lands == "heard_late" else 0)
    rec = outputs.recording()
    assert rec[cut - 1, 0] != 0 and not np.any(rec[cut:]), "silent from the cut on"


def test_an_estop_waits_for_a_block_under_way_before_opening_the_relays(outputs):
    """A driver inside the gate's fill (its thread starved under load, here held inside the
    source by the test) has not stopped pulling: the block it brings back was checked
    before the e-stop. The relays must not open on the "stopped pulling" timeout while
    the amplifiers still hold the signal's level; under load they did (57.5 V at relay 1)."""
    import threading

    from console.benchmarks.safety import FaultySource

    gate = outputs.gate
    start = fresh(outputs)
    outputs.set_relays({gate.relay_channels["PA"]})
    inside, release = threading.Event(), threading.Event()

    class HeldSource(FaultySource):  # core code on the audio thread, as the scheduler
        def next_block(self, n):
            if self.k >= 2048 and not release.is_set():
                inside.set()
                release.wait(10)
            return super().next_block(n)

    gate.attach_scheduler(HeldSource(ROUTES["PA"], 60.0, 250.0, "none", 10**6, 9600, FS))
    try:
        assert inside.wait(10)
        assert any(gate.level_v), "the amplifiers hold the signal's level"
        gate.estop("operator", wait=False)
        time.sleep(6 * outputs.limits.estop_timeout_s)  # the driver has not come back
        assert gate.relay_state() == frozenset({1}), "relays opened under signal"
    finally:
        release.set()
    assert gate.wait_safe(5)
    assert not [e for e in gate.events if "without observed silence" in e.message]
    check_received(outputs, start, ROUTES["PA"])


def test_an_estop_between_the_gates_look_and_its_call_to_a_source_ends_the_wait(outputs):
    """An e-stop landing after the gate looked at its flag (not e-stopped) and before it
    called the attached source ends the wait for that source at once: the e-stop does not
    wait out the source's stall time (a slow source here), nor turn into a stall fault."""
    from console.benchmarks.safety import FaultySource

    gate = outputs.gate
    start = fresh(outputs)
    outputs.set_relays({gate.relay_channels["PA"]})

    class SlowSource(FaultySource):
        def next_block(self, n):
            if self.k >= 2048:
                time.sleep(3 * outputs.limits.source_stall_s)
            return super().next_block(n)

    gate.attach(SlowSource(ROUTES["PA"], 30.0, 250.0, "none", 10**6, 9600, FS))
    caller = gate._caller
    call = caller.call
    landed = []

    def call_after_an_estop(fn, n, timeout_s, **kw):
        if fn.__self__.k >= 2048 and not landed:
            landed.append(gate.clock)
            gate.estop("operator", wait=False)
        return call(fn, n, timeout_s, **kw)

    caller.call = call_after_an_estop
    t_end = time.monotonic() + 10
    while not landed and time.monotonic() < t_end:
        time.sleep(0.001)
    assert landed and gate.wait_safe(5)
    since = [e for e in gate.events if e.t_s >= start.t0_s]
    assert [e.kind for e in since if e.kind in ("estop", "fault")] == ["estop"], since
    check_received(outputs, start, ROUTES["PA"])


def test_the_audit_sees_what_breaks_a_promise(outputs):
    """The checker itself: a step, a switch under signal and noise after an e-stop."""
    from console.safety import GateEvent

    lim = outputs.limits
    rec = np.zeros((2000, 2))
    start = Window(0, 0, 0.0)
    assert received_problems(lim, rec, [], [], start, ROUTES["PA"], BLOCK) == []
    stepped = rec.copy()
    stepped[500:, 0] = 100.0
    assert any(
        "steps" in p for p in received_problems(lim, stepped, [], [], start, ROUTES["PA"], BLOCK)
    )

    class Sw:
        channel, closed, clock, level_v = 1, False, 1200, (0.0, 0.0)

    noisy = rec.copy()
    noisy[1190, 0] = 0.5
    found = received_problems(lim, noisy, [Sw()], [], start, ROUTES["PA"], BLOCK)
    assert any("guard" in p for p in found)
    late = rec.copy()
    late[1500, 0] = 0.5
    ev = GateEvent(1.0, 100, "estop", "x")
    assert any(
        "e-stop" in p for p in received_problems(lim, late, [], [ev], start, ROUTES["PA"], BLOCK)
    )
    # a driver's cut to 0 V at an operator's e-stop is no slew step; a step back up from
    # that silence (the gate's ramp played after the cut) is one, however near the cut
    cut = rec.copy()
    cut[:1000, 0] = np.linspace(0.0, 60.0, 1000)  # a slow rise, cut to 0 V at 1000
    cut[1064:1067, 0] = [60.0 - 23.0, 60.0 - 46.0, 0.0]
    at_cut = GateEvent(1.0, 1040, "estop", "operator")
    step = lim.column_steps_v(ROUTES["PA"])[0]
    found = received_problems(lim, cut, [], [at_cut], start, ROUTES["PA"], BLOCK)
    assert found == [f"piezo steps 37.00 V at sample 1064 (limit {step:.2f})"], found
    cut[1064:1067, 0] = 0.0
    assert received_problems(lim, cut, [], [at_cut], start, ROUTES["PA"], BLOCK) == []
