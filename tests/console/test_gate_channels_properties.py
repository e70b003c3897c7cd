"""Property tests of the safety gate on five channels (a channel per patch and the screen),
with and without patch relays: whatever per-patch plans, bus plans, streams, attached
sources, relay commands and e-stops arrive, every channel the twin's amplifiers receive
stays inside its limits and its slew limit, relays switch in silence, and every channel is
silent within one block (plus the ramp down) of an e-stop."""

from __future__ import annotations

import contextlib

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from console.benchmarks.safety import (
    ROUTES,
    _estop_later,
    _finish,
    fresh_window,
    plan_case,
    relay_case,
    source_case,
)
from console.errors import SafetyRefusal
from console.profile import PROJECT_PROFILES, load_profile
from console.runtime.outputs import open_outputs
from console.safety_audit import Window, received_problems
from console.signals import ramp_envelope
from console.types import PATCHES, OutputPlan, Segment

FS = 48000
BLOCK = 64
PROPS = settings(
    max_examples=20,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
FAULTS = st.sampled_from(["none", "nan", "step", "raise", "object", "stall", "wrong_len"])


@pytest.fixture(scope="module", params=["no_relays", "relays"])
def outputs5(request, tmp_path_factory):
    from console.plugins import load_plugins

    plugins = load_plugins()
    text = (PROJECT_PROFILES / "sim-4ch.toml").read_text()
    if request.param == "relays":
        for i, p in enumerate(PATCHES, 1):
            text = text.replace(f"[patches.{p}]\n", f"[patches.{p}]\nrelay_channel = {i}\n")
    path = tmp_path_factory.mktemp("prof") / f"sim-4ch-{request.param}.toml"
    path.write_text(text)
    out = open_outputs(load_profile(str(path), plugins), plugins, fast=True)
    assert out.recording().shape[1] == 5
    yield out
    out.close()


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
    if fault == "nan":
        x[at % n] = np.nan
    elif fault == "step":
        x[at % n :] += step_v
        x[-1] = 0.0
    elif fault == "object":
        patch_v[victim] = x.astype(object)
    th = _estop_later(out, estop_s)
    with contextlib.suppress(SafetyRefusal):
        out.play(OutputPlan(FS, (Segment.per_patch(patch_v),), name="case"), timeout_s=10)
    _finish(out, th)
    return frozenset(patch_v)


@PROPS
@given(
    drives=st.dictionaries(
        st.sampled_from(PATCHES),
        st.tuples(st.floats(-95, 95), st.floats(20, 700)),
        min_size=1,
        max_size=4,
    ),
    fault=FAULTS,
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
    fault=FAULTS,
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
    amp=st.floats(0.5, 95),
    f=st.floats(20, 700),
    fault=FAULTS,
    at=st.integers(0, 6000),
    estop_s=st.none() | st.floats(0, 0.02),
    attach=st.booleans(),
)
def test_streams_and_attached_sources_with_faults(
    outputs5, route, amp, f, fault, at, estop_s, attach
):
    start = fresh_window(outputs5)
    source_case(outputs5, ROUTES[route], amp, f, fault, at, estop_s, attach)
    check_received(outputs5, start, ROUTES[route])


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
def test_relay_command_sequences(outputs5, cmds):
    start = fresh_window(outputs5)
    relay_case(outputs5, cmds)
    check_received(outputs5, start, frozenset({"PA"}))
    if outputs5.gate.estopped:
        assert outputs5.gate.relay_state() == frozenset()


class ChannelSource:
    """A source attached to the gate with a column per channel: a ramped sine on each of
    ``drives``' patches, misbehaving (``fault``) on one of them from sample ``at``."""

    idle = False

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
    outputs5, drives, fault, fault_patch, at, step_v, estop_s
):
    start = fresh_window(outputs5)
    route = frozenset(drives)
    with contextlib.suppress(SafetyRefusal):
        outputs5.set_relays({c for p in route if (c := outputs5.gate.relay_channels.get(p))})
    victim = sorted(route)[fault_patch % len(route)]
    names = outputs5.limits.channels
    outputs5.gate.attach(ChannelSource(names, drives, victim, fault, at, step_v))
    th = _estop_later(outputs5, estop_s)
    _finish(outputs5, th)
    check_received(outputs5, start, route)
