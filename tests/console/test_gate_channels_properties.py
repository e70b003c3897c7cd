"""Property tests of the safety gate on five channels (a channel per patch and the screen),
with and without patch relays: whatever per-patch plans, bus plans, streams, sources in
the scheduler's place, relay commands and e-stops arrive, every channel the twin's
amplifiers receive stays inside its limits and its slew limit, relays switch in silence,
and every channel is silent within one block (plus the ramp down) of an e-stop.

What a process can send its table's kernel goes through a kernel client (``outputs5``);
what takes the gate's or the scheduler's insides (sources in the scheduler's place, the
kernel's own synth breaking, direct gate switches) runs on the table's core built in this
process (``table5``)."""

from __future__ import annotations

import contextlib
import threading
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from console.benchmarks.safety import FAULTS as PLAN_FAULTS
from console.benchmarks.safety import (
    ROUTES,
    fresh_window,
    plan_case,
    relay_case,
    stream_case,
)
from console.config.profile import PROJECT_PROFILES, load_profile
from console.core.errors import SafetyRefusal
from console.core.types import PATCHES, OutputPlan, Segment
from console.kernel.client import open_outputs
from console.kernel.table import TableOutputs
from console.safety import Source
from console.safety.audit import Window, received_problems
from console.signals.stream_synth import PulseSpec, StreamSpec
from console.signals.waveforms import ramp_envelope, tone

FS = 48000
BLOCK = 64
PROPS = settings(
    max_examples=20,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
#: what a source in the scheduler's place or the kernel's synth can do wrong
FAULTS = st.sampled_from(["none", "nan", "step", "raise", "object", "stall", "wrong_len"])


@pytest.fixture(scope="module", params=["no_relays", "relays"])
def profile5(request, tmp_path_factory):
    """The sim-4ch profile (a channel per patch and the screen), with or without a relay
    per patch; and the plugins."""
    from console.config.plugins import load_plugins

    plugins = load_plugins()
    text = (PROJECT_PROFILES / "sim-4ch.toml").read_text()
    if request.param == "relays":
        for i, p in enumerate(PATCHES, 1):
            text = text.replace(f"[patches.{p}]\n", f"[patches.{p}]\nrelay_channel = {i}\n")
    path = tmp_path_factory.mktemp("prof") / f"sim-4ch-{request.param}.toml"
    path.write_text(text)
    return load_profile(str(path), plugins), plugins


@pytest.fixture(scope="module")
def outputs5(profile5):
    """A kernel client on a private fast-forward twin table of the five-channel profile."""
    out = open_outputs(*profile5, fast=True)
    assert out.recording().shape[1] == 5
    yield out
    out.close()


@pytest.fixture(scope="module")
def table5(profile5):
    """The five-channel profile's table core, built in this process."""
    t = TableOutputs(*profile5, fast=True)
    assert t.recording().shape[1] == 5
    yield t
    t.close()


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


def check_table(table: TableOutputs, start: Window, route: frozenset[str]) -> None:
    check_received(table, start, route, table.gate.events)


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


def estop_later(rig, delay_s: float | None) -> threading.Thread | None:
    """``rig.estop("case")`` ``delay_s`` from now, on a thread (None: no e-stop)."""
    if delay_s is None:
        return None
    th = threading.Thread(target=lambda: (time.sleep(delay_s), rig.estop("case")), daemon=True)
    th.start()
    return th


def finish_client(out, th: threading.Thread | None) -> None:
    """Let a client's case end: its e-stop thread joined, the queue empty, relays safe."""
    if th is not None:
        th.join()
    t_end = time.monotonic() + 10
    while out.status()["busy"] and time.monotonic() < t_end:
        time.sleep(0.001)
    assert out.wait_safe(5)


def finish_table(table: TableOutputs, th: threading.Thread | None) -> None:
    """Let a table core's case end: as ``finish_client``."""
    if th is not None:
        th.join()
    t_end = time.monotonic() + 10
    while table.scheduler.busy and time.monotonic() < t_end:
        time.sleep(0.001)
    assert table.gate.wait_safe(5)


def broken(x: np.ndarray, fault: str, step_v: float = 60.0) -> np.ndarray:
    """A block of volts broken by ``fault``."""
    if fault == "nan":
        x = x.copy()
        x[0] = np.nan
    elif fault == "step":
        x = x + step_v
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
    """Core code in the scheduler's place giving the bus pair ``(piezo, screen)``: a
    ramped sine, misbehaving (``fault``) from sample ``at`` on (on a five-channel gate the
    pair itself is a wrong block)."""

    def __init__(self, amp, f, fault, at, n_total=9600):
        self.amp, self.f, self.fault, self.at, self.n_total, self.k = amp, f, fault, at, n_total, 0

    @property
    def idle(self):
        return False

    def abort(self, reason):
        pass

    def next_block(self, n):
        if self.k >= self.n_total:
            return np.zeros(n), np.zeros(n)
        k = self.k + np.arange(n)
        x = self.amp * np.sin(2 * np.pi * self.f * k / FS) * np.minimum(1.0, k / 480)
        if self.k >= self.at:
            x = broken(x, self.fault)
        self.k += n
        return x, np.zeros(len(x))


def synth_case(table, route, amp, f, fault, at, estop_s) -> None:
    """The kernel's own synth of a live stream on ``route`` (a 200 ms piezo burst of
    ``amp`` V at ``f`` Hz) breaking from sample ``at`` of its output, maybe e-stopped
    meanwhile: no plugin code is on the audio path, the synth is what can go wrong."""
    spec = StreamSpec(
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
    th = estop_later(table, estop_s)
    with contextlib.suppress(SafetyRefusal):
        report, synth = table.scheduler.stream(spec, "broken")
        real = synth.next_block

        def next_block(n):
            k0 = synth.samples_out
            blk = real(n)
            if blk is None or k0 < at:
                return blk
            return broken(blk[0], fault), blk[1]

        synth.next_block = next_block  # this synth's own: it ends with the case
        synth.post([1])
        t_end = time.monotonic() + 0.3
        while not report.done.is_set() and time.monotonic() < t_end:
            time.sleep(0.001)
        synth.request_stop()
        report.wait(10)
    finish_table(table, th)


def attached_case(table, route, amp, f, fault, at, estop_s) -> None:
    """A source that misbehaves from sample ``at``, attached to the gate in the
    scheduler's place (the gate's only source: core code, called on the audio thread),
    always e-stopped in the end."""
    with contextlib.suppress(SafetyRefusal):  # a refused command is an outcome too
        # a patch without a relay (a channel of its own) is always connected
        table.set_relays({c for p in route if (c := table.gate.relay_channels.get(p))})
    table.gate.attach_scheduler(FaultySource(amp, f, fault, at))
    th = estop_later(table, estop_s if estop_s is not None else 0.03)
    t_end = time.monotonic() + 5
    while not table.gate.estopped and time.monotonic() < t_end:
        time.sleep(0.001)
    finish_table(table, th)


def per_patch_case(out, drives, fault, fault_patch, at, step_v, estop_s) -> frozenset[str]:
    """A per-patch plan (each patch its own amplitude and frequency), broken on one patch's
    drive by ``fault``, e-stopped ``estop_s`` after it is asked for; its patches."""
    n = 4800
    env = ramp_envelope(n, 480)
    patch_v = {
        p: amp * np.sin(2 * np.pi * f * np.arange(n) / FS) * env for p, (amp, f) in drives.items()
    }
    victim = sorted(patch_v)[fault_patch % len(patch_v)]
    x = patch_v[victim]
    if fault in ("nan", "inf"):
        x[at % n] = np.nan if fault == "nan" else np.inf
    elif fault == "step":
        x[at % n :] += step_v
        x[-1] = 0.0
    elif fault == "object":
        patch_v[victim] = x.astype(object)
    elif fault == "wrong_len":
        patch_v[victim] = x[:-1]
    th = estop_later(out, estop_s)
    with contextlib.suppress(SafetyRefusal):
        out.play(OutputPlan(FS, (Segment.per_patch(patch_v),), name="case"), timeout_s=10)
    finish_client(out, th)
    return frozenset(patch_v)


@PROPS
@given(
    drives=st.dictionaries(
        st.sampled_from(PATCHES),
        st.tuples(st.floats(-95, 95), st.floats(20, 700)),
        min_size=1,
        max_size=4,
    ),
    fault=st.sampled_from(PLAN_FAULTS),
    fault_patch=st.integers(0, 3),
    at=st.integers(0, 4800),
    step_v=st.floats(0, 200),
    estop_s=st.none() | st.floats(0, 0.02),
)
def test_per_patch_plans_with_faults(outputs5, drives, fault, fault_patch, at, step_v, estop_s):
    start = fresh_window(outputs5)
    route = per_patch_case(outputs5, drives, fault, fault_patch, at, step_v, estop_s)
    check_received(outputs5, start, route)


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
def test_bus_plans_with_faults(outputs5, route, amp, f, fault, at, step_at, step_v, estop_s):
    start = fresh_window(outputs5)
    plan_case(outputs5, ROUTES[route], amp, f, fault, at, step_at, step_v, estop_s)
    check_received(outputs5, start, ROUTES[route])


@PROPS
@given(
    route=st.sampled_from(sorted(ROUTES)),
    seed=st.integers(0, 2**32 - 1),
    estop_s=st.none() | st.floats(0, 0.02),
)
def test_streams_from_random_parameters_and_posts(outputs5, route, seed, estop_s):
    """Live streams as a client sends them: random (sometimes broken) parameters, good
    and garbage posts, stops and e-stops."""
    start = fresh_window(outputs5)
    stream_case(outputs5, ROUTES[route], np.random.default_rng(seed), estop_s)
    check_received(outputs5, start, ROUTES[route])


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
def test_broken_synths_and_attached_sources_with_faults(
    table5, route, amp, f, fault, at, estop_s, attach
):
    start = fresh_table(table5)
    if attach:
        attached_case(table5, ROUTES[route], amp, f, fault, at, estop_s)
    else:
        synth_case(table5, ROUTES[route], amp, f, fault, at, estop_s)
    check_table(table5, start, ROUTES[route])


@PROPS
@given(
    cmds=st.lists(
        st.tuples(
            st.sampled_from(["set", "play", "estop", "reset"]),
            st.frozensets(st.integers(1, 8), max_size=3),
        ),
        min_size=1,
        max_size=12,
    )
)
def test_relay_command_sequences(outputs5, cmds):
    start = fresh_window(outputs5)
    relay_case(outputs5, cmds)
    check_received(outputs5, start, frozenset({"PA"}))
    if outputs5.estopped:
        assert outputs5.wait_safe(5)
        assert outputs5.relay_state() == frozenset()
    else:
        assert outputs5.relay_state() == outputs5.operator_relays()


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
def test_relay_command_sequences_with_direct_gate_switches(table5, cmds):
    """As above, with switches asked of the gate directly (core code could): the gate
    refuses each that is not in silence, inside the rate limit, or during an e-stop."""
    start = fresh_table(table5)
    x = tone(250, 20.0, 0.05, FS, 0.01)
    plan = OutputPlan(FS, (Segment(x, np.zeros_like(x), ROUTES["PA"]),), name="p")
    for op, chans in cmds:
        try:
            if op == "set":
                table5.set_relays(chans, wait=False)
            elif op == "play":
                table5.play(plan, wait=False)
            elif op == "estop":
                table5.estop("case")
            elif op == "reset":
                assert table5.gate.wait_safe(5)
                table5.reset()
            else:
                table5.gate.switch_relays(frozenset(chans))
        except SafetyRefusal:
            continue
    finish_table(table5, None)
    check_table(table5, start, frozenset({"PA"}))
    if table5.gate.estopped:
        assert table5.gate.relay_state() == frozenset()


class ChannelSource(Source):
    """A source attached to the gate in the scheduler's place, a column per channel: a
    ramped sine on each of ``drives``' patches, misbehaving (``fault``) on one of them from
    sample ``at``."""

    @property
    def idle(self):
        return False

    def __init__(self, names, drives, victim, fault, at, step_v, n_total=9600):
        self.names, self.drives, self.victim = names, drives, victim
        self.fault, self.at, self.step_v, self.n_total, self.k = fault, at, step_v, n_total, 0

    def abort(self, reason):
        pass

    def next_block(self, n):
        k = self.k + np.arange(n)
        self.k += n
        cols = [np.zeros(n) for _ in self.names]
        if self.k > self.n_total:
            return tuple(cols)
        for p, (amp, f) in self.drives.items():
            x = amp * np.sin(2 * np.pi * f * k / FS) * np.minimum(1.0, k / 480)
            if p == self.victim and self.k - n >= self.at:
                if self.fault == "nan":
                    x[0] = np.nan
                elif self.fault == "step":
                    x = x + self.step_v
                elif self.fault == "wrong_len":
                    x = x[:-1]
                elif self.fault == "raise":
                    raise RuntimeError("effect crashed")
            cols[self.names.index(p)] = x
        return tuple(cols)


@PROPS
@given(
    drives=st.dictionaries(
        st.sampled_from(PATCHES),
        st.tuples(st.floats(-95, 95), st.floats(20, 700)),
        min_size=1,
        max_size=4,
    ),
    fault=st.sampled_from(["none", "nan", "step", "wrong_len", "raise"]),
    fault_patch=st.integers(0, 3),
    at=st.integers(0, 6000),
    step_v=st.floats(5, 200),
    estop_s=st.floats(0, 0.03),
)
def test_attached_sources_per_channel_with_faults(
    table5, drives, fault, fault_patch, at, step_v, estop_s
):
    start = fresh_table(table5)
    route = frozenset(drives)
    with contextlib.suppress(SafetyRefusal):
        table5.set_relays({c for p in route if (c := table5.gate.relay_channels.get(p))})
    victim = sorted(route)[fault_patch % len(route)]
    names = table5.limits.channels
    table5.gate.attach_scheduler(ChannelSource(names, drives, victim, fault, at, step_v))
    th = estop_later(table5, estop_s)
    finish_table(table5, th)
    check_table(table5, start, route)
