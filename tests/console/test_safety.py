"""The safety gate: nothing out of limits and no switch under signal ever reaches a driver."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from console.errors import SafetyRefusal
from console.safety import Limits, check_plan
from console.signals import ramp_envelope, tone
from console.types import PATCHES, OutputPlan, Segment

FS = 48000
HYP = settings(
    max_examples=40,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def assert_recording_safe(outputs) -> None:
    """Every sample the twin amplifiers received is inside the limits; every switch silent."""
    lim: Limits = outputs.limits
    rec = outputs.recording()
    lo, hi = lim.piezo_range()
    assert np.all(np.isfinite(rec))
    assert rec[:, 0].min(initial=0) >= lo - 1e-6 and rec[:, 0].max(initial=0) <= hi + 1e-6
    assert np.all(np.abs(rec[:, 1]) <= lim.screen_range()[1] + 1e-6)
    guard = lim.guard_samples
    for sw in outputs.relay_log():
        assert sw.level_v == (0.0, 0.0), sw
        before = rec[max(0, sw.clock - guard) : sw.clock]
        after = rec[sw.clock : sw.clock + lim.settle_samples]
        assert not np.any(before) and not np.any(after), f"signal near switch {sw}"


def seg_strategy():
    return st.builds(
        lambda n, f, amp, patches, screen_amp, ramp_ms: _segment(
            n, f, amp, patches, screen_amp, ramp_ms
        ),
        n=st.integers(600, 4000),
        f=st.floats(20, 700),
        amp=st.floats(0, 130),
        patches=st.sets(st.sampled_from(PATCHES), min_size=1),
        screen_amp=st.floats(0, 130),
        ramp_ms=st.floats(5.5, 10),
    )


def _segment(n, f, amp, patches, screen_amp, ramp_ms):
    env = ramp_envelope(n, round(ramp_ms * 1e-3 * FS))
    t = np.arange(n) / FS
    piezo = amp * np.sin(2 * np.pi * f * t) * env
    screen = screen_amp * np.sin(2 * np.pi * f * 0.7 * t) * env
    return Segment(piezo, screen, frozenset(patches), screen_amp > 0)


@HYP
@given(segs=st.lists(seg_strategy(), min_size=1, max_size=3))
def test_random_plans_play_inside_limits_or_are_refused(outputs, segs):
    outputs.reset()
    plan = OutputPlan(FS, tuple(segs), name="random")
    try:
        check_plan(plan, outputs.limits)
    except SafetyRefusal:
        with pytest.raises(SafetyRefusal):
            outputs.play(plan)
        assert_recording_safe(outputs)
        return
    report = outputs.play(plan)
    assert not report.error
    rec = outputs.recording()
    for seg, s, e in zip(plan.segments, report.segment_start, report.segment_end, strict=True):
        np.testing.assert_allclose(rec[s:e, 0], seg.piezo_v, atol=1e-4)
        np.testing.assert_allclose(rec[s:e, 1], seg.screen_v, atol=1e-4)
    assert_recording_safe(outputs)


BAD = st.sampled_from(["nan", "inf", "over", "under", "step", "tail", "screen_over", "no_patch"])


@HYP
@given(kind=BAD, where=st.floats(0, 1), size=st.floats(1.01, 50))
def test_bad_values_are_refused_never_clipped(outputs, kind, where, size):
    lim = outputs.limits
    sig = tone(250, 20, 0.1, FS, ramp_s=0.01)
    screen = np.zeros_like(sig)
    k = int(where * (sig.size - 1))
    patches = frozenset({"PA"})
    if kind == "nan":
        sig[k] = np.nan
    elif kind == "inf":
        sig[k] = np.inf
    elif kind == "over":
        sig[sig.size // 2] = lim.piezo_range()[1] * size
    elif kind == "under":
        sig[sig.size // 2] = lim.piezo_range()[0] * size
    elif kind == "step":
        sig = 20 * np.sin(2 * np.pi * 250 * np.arange(sig.size) / FS + 1.0)
        sig[-1] = 0
    elif kind == "tail":
        sig[-1] = 5.0
    elif kind == "screen_over":
        screen = tone(180, lim.screen_range()[1] * size, 0.1, FS)
    else:
        patches = frozenset()
    plan = OutputPlan(FS, (Segment(sig, screen, patches, True),), name=kind)
    before = len(outputs.recording())
    with pytest.raises(SafetyRefusal) as err:
        outputs.play(plan)
    assert "\n" not in str(err.value)
    time.sleep(0.002)
    assert not np.any(outputs.recording()[before:]), "a refused plan reached the amplifiers"
    assert_recording_safe(outputs)


class FailingStream:
    """An effect that raises mid-stimulus."""

    patches = frozenset({"PB"})
    screen = False

    def __init__(self, fail_after: int):
        self.k = 0
        self.fail_after = fail_after

    def next_block(self, n):
        if self.k >= self.fail_after:
            raise RuntimeError("effect crashed")
        t = (self.k + np.arange(n)) / FS
        env = np.minimum(1.0, (self.k + np.arange(n)) / 480)
        self.k += n
        return 30 * np.sin(2 * np.pi * 200 * t) * env, np.zeros(n)

    def request_stop(self):
        pass


def test_effect_raising_mid_stimulus_estops_and_opens_relays(outputs):
    report = outputs.stream(FailingStream(fail_after=4800))
    report.wait(10)
    assert outputs.gate.estopped and "effect crashed" in outputs.gate.estop_reason
    assert outputs.gate.wait_safe(5)
    assert outputs.gate.relay_state() == frozenset()
    time.sleep(0.01)
    rec = outputs.recording()
    assert np.any(rec[:, 0]), "the stream played before it crashed"
    assert not np.any(rec[-64:]), "outputs silent after the crash"
    assert_recording_safe(outputs)


def test_relay_driver_failure_estops_and_reports(outputs):
    board = outputs._board
    board.fail_on = {2}
    plan = OutputPlan(
        FS, (Segment(tone(250, 10, 0.05, FS, 0.01), np.zeros(2400), frozenset({"PB"})),), name="pb"
    )
    with pytest.raises(SafetyRefusal, match="relay"):
        outputs.play(plan)
    assert outputs.gate.estopped
    assert not np.any(outputs.recording()), "nothing played through a failed relay"
    assert outputs.gate.relay_state() == frozenset()


def test_audio_device_vanishing_silences(outputs):
    plan = OutputPlan(
        FS, (Segment(tone(250, 10, 2.0, FS), np.zeros(96000), frozenset({"PA"})),), name="long"
    )
    report = outputs.play(plan, wait=False)
    while not report.segment_start:
        time.sleep(0.001)
    outputs.gate.estop("audio device vanished")  # what a driver calls on PortAudioError
    report.wait(5)
    assert report.error and outputs.gate.relay_state() == frozenset()
    stop = [e for e in outputs.gate.events if e.kind == "estop"][0].clock
    rec = outputs.recording()
    block = outputs.limits.sample_rate_hz and 64
    assert not np.any(rec[stop + block :]), "e-stop silences within one audio block"


def test_switch_under_signal_is_refused_whatever_is_asked(outputs):
    plan = OutputPlan(FS, (Segment(tone(250, 10, 1.0, FS), np.zeros(48000), frozenset({"PA"})),))
    report = outputs.play(plan, wait=False)
    # the tone is at the amplifiers (a segment's start is reported as its first block is
    # made, before the gate has handed it over: a switch then meets the rate limit first)
    while not any(outputs.gate.level_v):
        time.sleep(0.001)
    with pytest.raises(SafetyRefusal, match="silent"):
        outputs.gate.switch_relays(frozenset({2}))
    # a queued toggle waits for silence instead
    toggle = outputs.set_relays({3}, wait=False)
    report.wait(10)
    toggle.wait(10)
    assert outputs.gate.relay_state() == frozenset({3})
    assert_recording_safe(outputs)


def test_estop_is_idempotent_and_blocks_until_reset(outputs):
    outputs.set_relays({1, 5})
    outputs.estop()
    outputs.estop()
    assert outputs.gate.relay_state() == frozenset()
    assert sum(e.kind == "estop" for e in outputs.gate.events) == 1
    plan = OutputPlan(
        FS, (Segment(tone(250, 10, 0.05, FS, 0.01), np.zeros(2400), frozenset({"PA"})),)
    )
    with pytest.raises(SafetyRefusal, match="e-stop"):
        outputs.play(plan)
    outputs.reset()
    outputs.play(plan)
    assert_recording_safe(outputs)


SCRIPT = textwrap.dedent("""
    import sys, time
    import numpy as np
    from console.plugins import load_plugins
    from console.profile import load_profile
    from console.runtime.outputs import open_outputs
    from console.signals import tone
    from console.types import OutputPlan, Segment
    log = open(sys.argv[1], "a", buffering=1)
    plugins = load_plugins()
    out = open_outputs(load_profile("sim", plugins), plugins)
    out.gate.listeners.append(lambda e: log.write(f"{e.kind} {e.message}\\n"))
    orig = out._board.set
    out._board.set = lambda ch, closed: (orig(ch, closed), log.write(f"relay {ch} {closed}\\n"))
    sig = tone(250, 10, 20.0, 48000)
    out.play(OutputPlan(48000, (Segment(sig, np.zeros_like(sig), frozenset({"PA"})),)), wait=False)
    time.sleep(0.3)
    log.write("playing\\n")
    MODE = sys.argv[2]
    if MODE == "raise":
        raise RuntimeError("boom")
    if MODE == "exit":
        sys.exit(0)
    time.sleep(30)
""")


@pytest.mark.parametrize("how", ["SIGTERM", "SIGINT", "raise", "exit"])
def test_estop_runs_on_signals_exceptions_and_exit(tmp_path, how):
    script = tmp_path / "run.py"
    script.write_text(SCRIPT)
    log = tmp_path / "log.txt"
    mode = how if how in ("raise", "exit") else "wait"
    proc = subprocess.Popen(
        [sys.executable, str(script), str(log), mode],
        env={**os.environ, "HAPTABLE_LOAD_ENTRYPOINTS": "0"},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    if how.startswith("SIG"):
        deadline = time.monotonic() + 20
        while (
            not log.exists() or "playing" not in log.read_text()
        ) and time.monotonic() < deadline:
            time.sleep(0.05)
        proc.send_signal(getattr(signal, how))
    proc.wait(timeout=30)
    text = log.read_text()
    assert "relay 1 True" in text, text
    after = text.split("playing", 1)[1]
    assert "estop" in after or "shutdown" in after, text
    assert "relay 1 False" in after, "the patch relay was opened on the way out"


def test_switch_log_lines_up_with_recording_after_other_outputs(profile, plugins):
    """Twin relay clocks count the samples of the outputs they belong to, not earlier ones."""
    from console.runtime.outputs import open_outputs
    from console.stimuli import make_stimulus

    with open_outputs(profile, plugins, fast=True) as first:
        first.play(make_stimulus("sine-PB", FS))
    with open_outputs(profile, plugins, fast=True) as out:
        report = out.play(make_stimulus("sine-PA", FS))
        closing = [r for r in out.relay_log() if r.closed]
        assert closing and closing[0].clock <= report.segment_start[0]
        assert_recording_safe(out)
