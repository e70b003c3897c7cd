"""Property tests of the safety gate with injected faults: whatever plans, streams, sources
in the scheduler's place, relay commands and e-stops arrive, the twin's amplifiers and
relays only ever see samples inside the limits and the slew limit, switches in silence,
and silence within one block (plus the ramp down) of an e-stop.

What a process can send its table's kernel (plans, stream parameters and posts, relay
commands, e-stops and resets) goes through a kernel client (``outputs``, the benchmark's
cases); what takes the gate's or the scheduler's insides (a source in the scheduler's
place, the kernel's own synth breaking, direct gate switches, e-stops landing inside a
fill) runs on the table's core built in this process (``table``)."""

from __future__ import annotations

import contextlib
import math
import threading
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from console.benchmarks.safety import (
    FAULTS as PLAN_FAULTS,
)
from console.benchmarks.safety import (
    ROUTES,
    fresh_window,
    plan_case,
    relay_case,
    stream_case,
)
from console.core.errors import SafetyRefusal
from console.core.types import OutputPlan, Segment
from console.kernel.table import TableOutputs
from console.safety import SafetyGate, Source
from console.safety.audit import Window, received_problems
from console.signals.stream_synth import PulseSpec, StreamSpec
from console.signals.waveforms import ramp_envelope, tone
from plugins.twin.outputs import TwinAudioOutput

FS = 48000
BLOCK = 64
PROPS = settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


fresh = fresh_window


def check_received(rig, start: Window, route: frozenset[str], events=None) -> None:
    """The audit on ``rig``'s twin (a kernel client or a ``TableOutputs``) since
    ``start``; ``events`` default to the client's."""
    problems = received_problems(
        rig.limits,
        rig.recording(),
        rig.relay_log(),
        rig.events() if events is None else list(events),
        start,
        route,
        BLOCK,
    )
    assert not problems, problems


# ------------------------------------------------------------ the table's core, in here
def fresh_table(table: TableOutputs) -> Window:
    """A clean table core: its e-stop reset, the scheduler the gate's source again,
    nothing queued; where the next case's records begin."""
    gate = table.gate
    if gate.estopped:
        assert gate.wait_safe(5)
        table.reset()
    gate.attach_scheduler(table.scheduler)
    t = time.monotonic() + 5
    while table.scheduler.busy and time.monotonic() < t:
        time.sleep(0.001)
    return Window(table.recording().shape[0], len(table.relay_log()), time.monotonic())


def check_table(table: TableOutputs, start: Window, route: frozenset[str]) -> None:
    check_received(table, start, route, table.gate.events)


def estop_later(table: TableOutputs, delay_s: float | None) -> threading.Thread | None:
    if delay_s is None:
        return None
    th = threading.Thread(target=lambda: (time.sleep(delay_s), table.estop("case")), daemon=True)
    th.start()
    return th


def finish(table: TableOutputs, th: threading.Thread | None) -> None:
    """Let a case end: its e-stop thread joined, the queue empty, the relays safe."""
    if th is not None:
        th.join()
    t_end = time.monotonic() + 10
    while table.scheduler.busy and time.monotonic() < t_end:
        time.sleep(0.001)
    assert table.gate.wait_safe(5)


def broken(x: np.ndarray, fault: str) -> np.ndarray:
    """A block of volts broken by ``fault``."""
    if fault == "nan":
        x = x.copy()
        x[0] = np.nan
    elif fault == "step":
        x = x + 60.0
    elif fault == "raise":
        raise RuntimeError("effect crashed")
    elif fault == "object":
        x = x.astype(object)
    elif fault == "stall":
        time.sleep(0.15)
    elif fault == "wrong_len":
        x = x[:-1]
    return x


class FaultySource(Source):
    """Core code in the scheduler's place (the gate's only source, on the audio thread):
    a ramped sine that misbehaves (``fault``) from sample ``at`` on, silence after
    ``n_total`` samples."""

    def __init__(self, route, amp, f, fault, at, n_total, fs=FS):
        self.route, self.amp, self.f, self.fault, self.at = route, amp, f, fault, at
        self.n_total, self.fs, self.k = n_total, fs, 0

    @property
    def idle(self):
        return False

    def abort(self, reason):
        pass

    def next_block(self, n):
        if self.k >= self.n_total:
            return np.zeros(n), np.zeros(n)
        k = self.k + np.arange(n)
        x = self.amp * np.sin(2 * np.pi * self.f * k / self.fs) * np.minimum(1.0, k / 480)
        if self.k >= self.at:
            x = broken(x, self.fault)
        self.k += n
        return x, np.zeros(len(x))


def synth_spec(route, amp: float, f: float) -> StreamSpec:
    """A live stream on ``route``: a 200 ms piezo burst of ``amp`` V at ``f`` Hz."""
    return StreamSpec(
        sample_rate_hz=FS,
        patches=route,
        screen=False,
        carrier_max_v=0.0,
        carrier_min_hz=60,
        carrier_max_hz=400,
        start_hz=180,
        glide_ms=10,
        ramp_ms=10,
        pulse=PulseSpec("burst", "piezo", amp, f, 200.0, 0),
    )


def broken_synth_stream(table, monkeypatch, route, amp, f, fault, at):
    """The kernel's own synth of a burst stream, breaking (``fault``) from sample ``at``
    of its output: no plugin code is on the audio path, the synth is what can go wrong
    there. Its report."""
    report, synth = table.scheduler.stream(synth_spec(route, amp, f), "broken")
    real = synth.next_block

    def next_block(n):
        k0 = synth.samples_out
        blk = real(n)
        if blk is None or k0 < at:
            return blk
        return broken(blk[0], fault), blk[1]

    monkeypatch.setattr(synth, "next_block", next_block)
    synth.post([1])
    return report, synth


def attached_case(table, route, amp, f, fault, at, estop_s) -> None:
    """A source that misbehaves from sample ``at``, attached to the gate in the
    scheduler's place, always e-stopped in the end."""
    with contextlib.suppress(SafetyRefusal):  # a refused command is an outcome too
        # a patch without a relay (a channel of its own) is always connected
        table.set_relays({c for p in route if (c := table.gate.relay_channels.get(p))})
    table.gate.attach_scheduler(FaultySource(route, amp, f, fault, at, 9600))
    th = estop_later(table, estop_s if estop_s is not None else 0.03)
    t_end = time.monotonic() + 5
    while not table.gate.estopped and time.monotonic() < t_end:
        time.sleep(0.001)
    finish(table, th)


def synth_case(table, monkeypatch, route, amp, f, fault, at, estop_s) -> None:
    """The kernel's synth breaking from sample ``at`` (maybe e-stopped meanwhile)."""
    th = estop_later(table, estop_s)
    with contextlib.suppress(SafetyRefusal):
        report, synth = broken_synth_stream(table, monkeypatch, route, amp, f, fault, at)
        t_end = time.monotonic() + 0.3
        while not report.done.is_set() and time.monotonic() < t_end:
            time.sleep(0.001)
        synth.request_stop()
        report.wait(10)
    finish(table, th)


# ------------------------------------------------------------------------- properties
SOURCE_FAULTS = st.sampled_from(["none", "nan", "step", "raise", "object", "stall", "wrong_len"])


def signal(n: int, amp: float, f: float) -> np.ndarray:
    t = np.arange(n) / FS
    return amp * np.sin(2 * np.pi * f * t) * ramp_envelope(n, 480)


@PROPS
@given(
    route=st.sampled_from(sorted(ROUTES)),
    amp=st.floats(0.5, 95),
    f=st.floats(20, 700),
    fault=st.sampled_from(PLAN_FAULTS),
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
    seed=st.integers(0, 2**32 - 1),
    estop_s=st.none() | st.floats(0, 0.02),
)
def test_streams_from_random_parameters_and_posts(outputs, route, seed, estop_s):
    """Live streams as a client sends them: random (sometimes broken) parameters, good
    and garbage posts, stops and e-stops."""
    start = fresh(outputs)
    stream_case(outputs, ROUTES[route], np.random.default_rng(seed), estop_s)
    check_received(outputs, start, ROUTES[route])


@PROPS
@given(
    route=st.sampled_from(sorted(ROUTES)),
    amp=st.floats(0.5, 95),
    f=st.floats(20, 700),
    fault=SOURCE_FAULTS,
    at=st.integers(0, 6000),
    estop_s=st.none() | st.floats(0, 0.02),
    attach=st.booleans(),
)
def test_broken_synths_and_attached_sources_with_faults(
    table, monkeypatch, route, amp, f, fault, at, estop_s, attach
):
    start = fresh_table(table)
    with monkeypatch.context() as mp:
        if attach:
            attached_case(table, ROUTES[route], amp, f, fault, at, estop_s)
        else:
            synth_case(table, mp, ROUTES[route], amp, f, fault, at, estop_s)
    check_table(table, start, ROUTES[route])


RELAY_CMDS = st.lists(
    st.tuples(
        st.sampled_from(["set", "play", "estop", "reset"]),
        st.frozensets(st.integers(1, 8), max_size=3),
    ),
    min_size=1,
    max_size=12,
)


@PROPS
@given(cmds=RELAY_CMDS)
def test_relay_command_sequences(outputs, cmds):
    start = fresh(outputs)
    relay_case(outputs, cmds)
    check_received(outputs, start, frozenset({"PA"}))
    if outputs.estopped:
        assert outputs.wait_safe(5)
        assert outputs.relay_state() == frozenset()
    else:
        assert outputs.relay_state() == outputs.operator_relays()


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
def test_relay_command_sequences_with_direct_gate_switches(table, cmds):
    """As above, with switches asked of the gate directly (core code could): the gate
    refuses each that is not in silence, inside the rate limit, or during an e-stop."""
    start = fresh_table(table)
    x = tone(250, 20.0, 0.05, FS, 0.01)
    plan = OutputPlan(FS, (Segment(x, np.zeros_like(x), ROUTES["PA"]),), name="p")
    for op, chans in cmds:
        try:
            if op == "set":
                table.set_relays(chans, wait=False)
            elif op == "play":
                table.play(plan, wait=False)
            elif op == "estop":
                table.estop("case")
            elif op == "reset":
                assert table.gate.wait_safe(5)
                table.reset()
            else:
                table.gate.switch_relays(frozenset(chans))
        except SafetyRefusal:
            continue
    finish(table, None)
    check_table(table, start, frozenset({"PA"}))
    if table.gate.estopped:
        assert table.gate.relay_state() == frozenset()


@pytest.mark.parametrize("fault", ["raise", "nan", "wrong_len", "step", "stall"])
def test_the_audio_thread_survives_every_fault(table, monkeypatch, fault):
    """The kernel's synth breaking on the audio thread: the per-block checks e-stop
    (a stall only delays the blocks), and the thread goes on to play the next plan."""
    start = fresh_table(table)
    with monkeypatch.context() as mp:
        report, synth = broken_synth_stream(table, mp, ROUTES["PA"], 10.0, 200.0, fault, 960)
        if fault == "stall":
            t_end = time.monotonic() + 0.5
            while not report.done.is_set() and time.monotonic() < t_end:
                time.sleep(0.001)
            synth.request_stop()
        report.wait(10)
    if fault == "stall":
        assert not report.error and not table.gate.estopped
    else:
        assert report.error and table.gate.estopped
    assert table.gate.wait_safe(5)
    check_table(table, start, ROUTES["PA"])
    c0 = table.gate.clock
    table.reset()
    x = signal(2400, 10.0, 250.0)
    table.play(OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),)))
    assert table.gate.clock > c0


@pytest.fixture
def held_table(profile, plugins, monkeypatch):
    """The sim profile's table core whose twin driver hears the gate's events only when
    ``hold`` is empty (a test holds them back in ``held`` and hands them on later)."""
    hold: list[bool] = []
    held: list = []
    real = TwinAudioOutput._on_gate_event

    def on_gate_event(self, ev):
        if hold:
            held.append(ev)
        else:
            real(self, ev)

    monkeypatch.setattr(TwinAudioOutput, "_on_gate_event", on_gate_event)
    t = TableOutputs(profile, plugins, fast=True)
    t.hold, t.held, t.hear = hold, held, lambda ev: real(t.audio, ev)
    yield t
    hold.clear()
    t.close()


@pytest.mark.parametrize("lands", ["before", "after", "heard_late"])
def test_an_estop_landing_as_a_loud_block_is_handed_over_stays_silent(
    held_table, lands, monkeypatch
):
    """An operator's e-stop landing while the gate hands over a loud block it has already
    checked: its event takes the clock of the block's first sample ("before", "heard_late")
    or of its end ("after"), and the driver hears it before it stores the block (drops
    it) or, "heard_late", only after (plays it whole and drops the next). Either way the
    twin ramps from the level at the cut at the slew step and drops the rest of the
    gate's ramp down: played after the cut, its first sample (the block's last level less
    one slew step) stepped the amplifiers up from 0 V, as the property test above met
    under load; and the audit finds no step anywhere. Here the timing is injected."""
    table = held_table
    gate = table.gate
    route = ROUTES["PA"]
    step_v = float(table.limits.column_steps_v(route)[0])
    start = fresh_table(table)
    table.set_relays({gate.relay_channels["PA"]})
    hand = SafetyGate._hand  # the sealed gate takes no patch of its own: the class's
    landed: list[int] = []  # the clock of the block the e-stop landed on

    def hand_with_estop(self, out, cols):
        if self is not gate:
            hand(self, out, cols)
            return
        if table.held:  # the next block (the gate's ramp down): the driver hears it now
            table.hold.clear()
            for ev in table.held:
                table.hear(ev)
            table.held.clear()
        if landed or abs(float(cols[0][-1])) <= 2.2 * step_v:  # a ramp down of 3+ samples
            hand(self, out, cols)
            return
        landed.append(gate.clock)
        if lands == "heard_late":
            table.hold.append(True)  # the driver hears this e-stop a block late
        if lands != "after":
            gate.estop("operator", wait=False)
        hand(self, out, cols)
        if lands == "after":
            gate.estop("operator", wait=False)

    monkeypatch.setattr(SafetyGate, "_hand", hand_with_estop)
    gate.attach_scheduler(FaultySource(route, 90.0, 250.0, "none", 10**6, 9600))
    t_end = time.monotonic() + 10
    while not gate.estopped and time.monotonic() < t_end:
        time.sleep(0.001)
    assert gate.wait_safe(5)
    monkeypatch.undo()
    assert landed and not table.held and not table.hold, "the e-stop never landed"
    stop = [e for e in gate.events if e.kind == "estop" and e.t_s >= start.t0_s][0]
    assert stop.clock == landed[0] + (BLOCK if lands == "after" else 0)
    check_table(table, start, route)
    cut = landed[0] + (BLOCK if lands == "heard_late" else 0)
    rec = table.recording()
    assert rec[cut - 1, 0] != 0, "loud when the e-stop landed"
    quiet = cut + math.ceil(abs(rec[cut - 1, 0]) / step_v)
    assert not np.any(rec[quiet:]), "silent from the end of the ramp down on"


def test_an_estop_waits_for_a_block_under_way_before_opening_the_relays(table):
    """A driver inside the gate's fill (its thread starved under load, here held inside the
    source by the test) has not stopped pulling: the block it brings back was checked
    before the e-stop. The relays must not open on the "stopped pulling" timeout while
    the amplifiers still hold the signal's level; under load they did (57.5 V at relay 1)."""
    gate = table.gate
    start = fresh_table(table)
    table.set_relays({gate.relay_channels["PA"]})
    inside, release = threading.Event(), threading.Event()

    class HeldSource(FaultySource):  # core code on the audio thread, as the scheduler
        def next_block(self, n):
            if self.k >= 2048 and not release.is_set():
                inside.set()
                release.wait(10)
            return super().next_block(n)

    gate.attach_scheduler(HeldSource(ROUTES["PA"], 60.0, 250.0, "none", 10**6, 9600))
    try:
        assert inside.wait(10)
        assert any(gate.level_v), "the amplifiers hold the signal's level"
        gate.estop("operator", wait=False)
        time.sleep(6 * table.limits.estop_timeout_s)  # the driver has not come back
        assert gate.relay_state() == frozenset({1}), "relays opened under signal"
    finally:
        release.set()
    assert gate.wait_safe(5)
    assert not [e for e in gate.events if "without observed silence" in e.message]
    check_table(table, start, ROUTES["PA"])


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
    # the twin driver ramps at an operator's e-stop too: a cut to 0 V at the e-stop is a
    # step like any other (no exemption at a cut), and so is a step back up from silence
    cut = rec.copy()
    cut[:1000, 0] = np.linspace(0.0, 60.0, 1000)  # a slow rise, cut to 0 V at 1000
    at_cut = GateEvent(1.0, 1000, "estop", "operator")
    step = lim.column_steps_v(ROUTES["PA"])[0]
    found = received_problems(lim, cut, [], [at_cut], start, ROUTES["PA"], BLOCK)
    assert found == [f"piezo steps 60.00 V at sample 1000 (limit {step:.2f})"], found
    cut[1000:1003, 0] = [60 - step, 60 - 2 * step, 0.0]  # ramped down at the slew step
    assert received_problems(lim, cut, [], [at_cut], start, ROUTES["PA"], BLOCK) == []
    cut[1064:1067, 0] = [60.0 - 23.0, 60.0 - 46.0, 0.0]  # the gate's ramp played late
    found = received_problems(lim, cut, [], [at_cut], start, ROUTES["PA"], BLOCK)
    assert found == [f"piezo steps 37.00 V at sample 1064 (limit {step:.2f})"], found
