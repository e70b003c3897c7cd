"""Property tests of the safety gate with injected faults: whatever plans, streams, attached
sources, relay commands and e-stops arrive, the twin's amplifiers and relays only ever see
samples inside the limits and the slew limit, switches in silence, and silence within one
block (plus the ramp down) of an e-stop."""

from __future__ import annotations

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
