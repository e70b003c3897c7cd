"""The safety gate: nothing out of limits and no switch under signal ever reaches a driver."""

from __future__ import annotations

import dataclasses
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

from console.core.errors import SafetyRefusal
from console.core.types import PATCHES, OutputPlan, Segment
from console.kernel.table import DriverPort
from console.safety import Limits, check_plan
from console.signals.stream_synth import PulseSpec, StreamSpec, StreamSynth
from console.signals.waveforms import ramp_envelope, tone

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


def burst_spec(**pulse) -> StreamSpec:
    """A live stream's parameters: a 30 V, 200 Hz piezo burst on PB, 200 ms long, at
    each posted crossing."""
    kw = dict(shape="burst", channel="piezo", peak_v=30.0, freq_hz=200.0, length_ms=200.0)
    kw.update(edge_ms=0, **pulse)
    return StreamSpec(
        sample_rate_hz=FS,
        patches=frozenset({"PB"}),
        screen=False,
        carrier_max_v=0.0,
        carrier_min_hz=60,
        carrier_max_hz=400,
        start_hz=180,
        glide_ms=10,
        ramp_ms=10,
        pulse=PulseSpec(**kw),
    )


def test_kernel_synth_raising_mid_stream_estops_and_opens_relays(table, monkeypatch):
    """No plugin code runs on the audio path any more: what can raise there is the
    kernel's own synth. It breaks mid-pulse; the gate's per-block guard e-stops, ramps
    down from where it was and opens the relays."""
    real = StreamSynth.next_block

    def crashing(self, n):
        if self.samples_out >= 4800:
            raise RuntimeError("effect crashed")
        return real(self, n)

    monkeypatch.setattr(StreamSynth, "next_block", crashing)
    report, synth = table.scheduler.stream(burst_spec(), "effect")
    synth.post([1])
    report.wait(10)
    assert table.gate.estopped and "effect crashed" in table.gate.estop_reason
    assert report.error
    assert table.gate.wait_safe(5)
    assert table.gate.relay_state() == frozenset()
    time.sleep(0.01)
    rec = table.recording()
    s = report.segment_start[0]
    assert np.abs(rec[s : s + 4800, 0]).max() > 20, "the stream played before it crashed"
    assert np.abs(rec[s + 4736 : s + 4800, 0]).max() > 20, "it crashed mid-pulse"
    assert not np.any(rec[-64:]), "outputs silent after the crash"
    assert_recording_safe(table)


class SpecOf:
    """What a client hands ``stream``: an object with a ``spec``, bound to the kernel's
    side of the stream (``sink``) once it opened."""

    def __init__(self, spec):
        self.spec, self.sink = spec, None

    def bind(self, sink):
        self.sink = sink


class RawSpec:
    """Parameters that were never a ``StreamSpec``: its JSON only."""

    def __init__(self, **changes):
        self.d = {**burst_spec().to_json(), **changes}

    def to_json(self):
        return self.d


@pytest.mark.parametrize(
    "spec, why",
    [
        (burst_spec(peak_v=1e6), "outside the limits"),
        (dataclasses.replace(burst_spec(), sample_rate_hz=44100), "sample_rate_hz"),
        (dataclasses.replace(burst_spec(), ramp_ms=1.0), "ramp_ms"),
        (RawSpec(carrier_max_v=-5.0), "carrier_max_v"),
        (RawSpec(carrier_max_v=float("nan")), "not sent"),
        (RawSpec(patches=["PZ"]), "patches"),
        (RawSpec(screen="yes"), "screen"),
        (RawSpec(extra=1), "unknown key"),
    ],
)
def test_bad_stream_parameters_are_refused_at_open(outputs, spec, why):
    """A client's stream is parameters, checked when it asks: broken or out-of-limits
    ones are refused in one line, nothing plays and nothing e-stops."""
    bad = SpecOf(spec)
    with pytest.raises(SafetyRefusal) as err:
        outputs.stream(bad, "bad")
    assert bad.sink is None, "a refused stream is never bound"
    assert why in str(err.value) and "\n" not in str(err.value)
    assert not outputs.estopped and not outputs.status()["busy"]
    assert outputs.relay_state() == frozenset()
    assert not np.any(outputs.recording()), "a refused stream reached the amplifiers"
    # the table still plays a good one
    good = SpecOf(burst_spec(length_ms=20.0))
    report = outputs.stream(good, "good")
    good.sink.post([1])
    time.sleep(0.05)
    good.sink.request_stop()
    report.wait(10)
    assert not report.error and np.abs(outputs.recording()[:, 0]).max() > 20
    assert_recording_safe(outputs)


def test_relay_driver_failure_estops_and_reports(table):
    table.board.fail_on = {2}
    plan = OutputPlan(
        FS, (Segment(tone(250, 10, 0.05, FS, 0.01), np.zeros(2400), frozenset({"PB"})),), name="pb"
    )
    with pytest.raises(SafetyRefusal, match="relay"):
        table.play(plan)
    assert table.gate.estopped and "relay board failed" in table.gate.estop_reason
    assert not np.any(table.recording()), "nothing played through a failed relay"
    assert table.gate.relay_state() == frozenset()


def test_audio_device_vanishing_silences(table):
    plan = OutputPlan(
        FS, (Segment(tone(250, 10, 2.0, FS), np.zeros(96000), frozenset({"PA"})),), name="long"
    )
    report = table.play(plan, wait=False)
    while not report.segment_start:
        time.sleep(0.001)
    # what a driver calls on PortAudioError, through the port it was started with
    DriverPort(table.gate).estop("audio device vanished")
    report.wait(5)
    assert report.error
    assert table.gate.wait_safe(5) and table.gate.relay_state() == frozenset()
    assert "audio device vanished" in table.gate.estop_reason
    stop = [e for e in table.gate.events if e.kind == "estop"][0].clock
    rec = table.recording()
    assert np.any(rec[report.segment_start[0] : stop]), "the tone was playing"
    block = 64
    assert not np.any(rec[stop + block :]), "e-stop silences within one audio block"
    assert_recording_safe(table)


def test_switch_under_signal_is_refused_whatever_is_asked(table):
    plan = OutputPlan(FS, (Segment(tone(250, 10, 1.0, FS), np.zeros(48000), frozenset({"PA"})),))
    report = table.play(plan, wait=False)
    # the tone is at the amplifiers (a segment's start is reported as its first block is
    # made, before the gate has handed it over: a switch then meets the rate limit first)
    while not any(table.gate.level_v):
        time.sleep(0.001)
    with pytest.raises(SafetyRefusal, match="silent"):
        table.gate.switch_relays(frozenset({2}))
    # a queued toggle waits for silence instead
    toggle = table.set_relays({3}, wait=False)
    report.wait(10)
    toggle.wait(10)
    assert not report.error and not toggle.error
    assert table.gate.relay_state() == frozenset({3})
    assert_recording_safe(table)


def test_estop_is_idempotent_and_blocks_until_reset(outputs):
    outputs.set_relays({1, 5})
    assert outputs.relay_state() == frozenset({1, 5})
    first = outputs.estop()
    outputs.estop()
    assert first["confirmed"], first
    assert outputs.relay_state() == frozenset()
    assert sum(e.kind == "estop" for e in outputs.events()) == 1
    plan = OutputPlan(
        FS, (Segment(tone(250, 10, 0.05, FS, 0.01), np.zeros(2400), frozenset({"PA"})),)
    )
    with pytest.raises(SafetyRefusal, match="e-stop"):
        outputs.play(plan)
    with pytest.raises(SafetyRefusal, match="e-stop"):
        outputs.set_relays({1})
    outputs.reset()
    assert not outputs.estopped and not outputs.status()["gate"]["estopped"]
    outputs.play(plan)
    assert_recording_safe(outputs)


SCRIPT = textwrap.dedent("""
    import faulthandler, signal, sys, time
    faulthandler.register(signal.SIGUSR2, all_threads=True)  # where it hangs, if it does
    # Ctrl-C as in a user's shell: an ignored SIGINT is inherited across exec, and a test
    # before this one in the worker may have left it ignored
    signal.signal(signal.SIGINT, signal.default_int_handler)
    import numpy as np
    from console.config.plugins import load_plugins
    from console.config.profile import load_profile
    from console.kernel.client import open_outputs
    from console.signals.waveforms import tone
    from console.core.types import OutputPlan, Segment
    log = open(sys.argv[1], "a", buffering=1)
    plugins = load_plugins()
    out = open_outputs(load_profile("sim", plugins), plugins)  # the table's kernel
    sig = tone(250, 10, 20.0, 48000)
    plan = OutputPlan(48000, (Segment(sig, np.zeros_like(sig), frozenset({"PA"})),))
    report = out.play(plan, wait=False)
    t_end = time.monotonic() + 20
    while report.t_first_sample_s is None and time.monotonic() < t_end:
        time.sleep(0.01)
    time.sleep(0.3)
    log.write(f"playing relays {sorted(out.relay_state())}\\n")
    import os
    t_end = time.monotonic() + 20
    while not os.path.exists(sys.argv[1] + ".go") and time.monotonic() < t_end:
        time.sleep(0.01)  # the test has seen it play: now end as asked
    MODE = sys.argv[2]
    if MODE == "raise":
        raise RuntimeError("boom")
    if MODE == "exit":
        sys.exit(0)
    time.sleep(30)
""")


@pytest.mark.parametrize("how", ["SIGTERM", "SIGINT", "raise", "exit"])
def test_a_client_ending_by_signal_exception_or_exit_leaves_the_table_safe(
    tmp_path, profile, plugins, how
):
    """The outputs live in the table's kernel: a process playing there that ends in any
    way (killed by a signal, an exception, ``sys.exit``) has what it played ramped down
    and the patch relay opened in silence by the kernel. Watched from a second client of
    the same (paced) table, which keeps its kernel up to be asked."""
    from console.kernel.client import open_outputs
    from console.safety.audit import Window, received_problems

    script = tmp_path / "run.py"
    script.write_text(SCRIPT)
    log = tmp_path / "log.txt"
    mode = how if how in ("raise", "exit") else "wait"
    with open_outputs(profile, plugins) as watch:
        assert not watch.table.private  # the script's table: the profile's own
        inherited = signal.getsignal(signal.SIGINT)
        proc = subprocess.Popen(
            [sys.executable, str(script), str(log), mode],
            env={**os.environ, "HAPTABLE_LOAD_ENTRYPOINTS": "0"},
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
        )
        try:
            deadline = time.monotonic() + 40
            while (
                not log.exists() or "playing" not in log.read_text()
            ) and time.monotonic() < deadline:
                assert proc.poll() is None, proc.communicate()
                time.sleep(0.05)
            assert "playing relays [1]" in log.read_text(), proc.communicate()
            assert any(watch.status()["gate"]["level_v"]), "the tone plays"
            (tmp_path / "log.txt.go").touch()
            if how.startswith("SIG"):
                proc.send_signal(getattr(signal, how))
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.send_signal(signal.SIGUSR2)  # its threads' stacks on stderr
                time.sleep(1.0)
                proc.kill()
                err = proc.communicate()[1].decode(errors="replace")
                pytest.fail(
                    f"{how}: still running after 30 s (worker SIGINT {inherited!r}):\n{err}"
                )
        finally:
            if proc.poll() is None:
                proc.kill()
        t_end = time.monotonic() + 10
        while (watch.status()["busy"] or watch.relay_state()) and time.monotonic() < t_end:
            time.sleep(0.02)
        assert not watch.status()["busy"], "what the client played was dropped"
        assert watch.relay_state() == frozenset(), "the patch relay was opened on the way out"
        st = watch.status()["gate"]
        assert not any(st["level_v"])
        assert not watch.estopped, "a client leaving is no e-stop: nothing is latched"
        rec = watch.recording()
        ch1 = [r for r in watch.relay_log() if r.channel == 1]
        assert ch1[0].closed and not ch1[-1].closed and len(ch1) == 2, ch1
        assert np.abs(rec[ch1[0].clock : ch1[1].clock, 0]).max() > 5, "the tone played"
        assert not np.any(rec[ch1[1].clock - watch.limits.guard_samples :])
        assert_recording_safe(watch)
        problems = received_problems(
            watch.limits,
            rec,
            watch.relay_log(),
            watch.events(),
            Window(0, 0, 0.0),
            frozenset({"PA"}),
            int(watch.status()["latency_samples"]),
        )
        assert not problems, problems  # ramped down at the slew limit, never cut


def test_switch_log_lines_up_with_recording_after_other_outputs(profile, plugins):
    """Twin relay clocks count the samples of the outputs they belong to, not earlier ones."""
    from console.kernel.client import open_outputs
    from console.signals.stimuli import make_stimulus

    with open_outputs(profile, plugins, fast=True) as first:
        first.play(make_stimulus("sine-PB", FS))
    with open_outputs(profile, plugins, fast=True) as out:
        report = out.play(make_stimulus("sine-PA", FS))
        closing = [r for r in out.relay_log() if r.closed]
        assert closing and closing[0].clock <= report.segment_start[0]
        assert_recording_safe(out)
