"""What used to get past the safety gate (issue: "no way past the gate"), each reproduced
on the twin and checked on what the twin's amplifiers and relays received: through a
kernel client (``outputs``) where a process could do it, on the table's core built here
(``table``) where it takes the gate's or the scheduler's insides."""

from __future__ import annotations

import contextlib
import threading
import time

import numpy as np
import pytest

from console.core.errors import SafetyRefusal
from console.core.types import OutputPlan, Segment
from console.safety import Source
from console.signals.stream_synth import PulseSpec, StreamSpec
from console.signals.waveforms import tone

FS = 48000


def max_steps(outputs) -> np.ndarray:
    """Largest sample-to-sample change the twin amplifiers received, per channel."""
    rec = outputs.recording()
    if rec.shape[0] < 2:
        return np.zeros(2)
    d = np.abs(np.diff(np.vstack([np.zeros((1, 2)), rec]), axis=0))
    return d.max(axis=0)


def assert_within_slew(outputs, patches=("PA",)) -> None:
    lim = outputs.limits
    piezo, screen = max_steps(outputs)
    assert piezo <= lim.max_step_v("piezo", frozenset(patches)) * 1.001 + 1e-9, piezo
    assert screen <= lim.max_step_v("screen") * 1.001 + 1e-9, screen


def wait_until(cond, timeout_s=10.0):
    t = time.monotonic() + timeout_s
    while not cond():
        assert time.monotonic() < t, "timed out"
        time.sleep(0.002)


# ---------------------------------------------------------------- 1. steps inside a segment
def test_step_inside_a_segment_is_refused(outputs):
    x = np.zeros(4800)
    x[1000:3000] = 100.0
    plan = OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),), name="step")
    with pytest.raises(SafetyRefusal, match="slew"):
        outputs.play(plan)
    assert not np.any(outputs.recording())


def test_sine_jumping_mid_segment_is_refused(outputs):
    x = tone(250, 1.0, 0.2, FS, 0.01)
    x[4000:6000] *= 100.0
    plan = OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),), name="jump")
    with pytest.raises(SafetyRefusal, match="slew"):
        outputs.play(plan)


def test_paper_waveforms_stay_within_the_slew_limit(outputs):
    lim = outputs.limits
    full = lim.piezo_card_v  # the sound card's full scale at the patches
    x = tone(625, full, 0.1, FS, 0.01)
    outputs.play(OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),)))
    pall = tone(625, 0.95 * min(full, 100.0), 0.1, FS, 0.01)
    outputs.play(
        OutputPlan(FS, (Segment(pall, np.zeros_like(pall), frozenset({"PA", "PB", "PC", "PD"})),))
    )
    assert not outputs.estopped and not outputs.status()["gate"]["estopped"]


def stream_spec(peak_v: float) -> StreamSpec:
    """A live stream on PA declaring a piezo peak of ``peak_v`` (a burst per crossing)."""
    return StreamSpec(
        sample_rate_hz=FS,
        patches=frozenset({"PA"}),
        screen=False,
        carrier_max_v=0.0,
        carrier_min_hz=60,
        carrier_max_hz=400,
        start_hz=180,
        glide_ms=10,
        ramp_ms=10,
        pulse=PulseSpec("burst", "piezo", peak_v, 200.0, 50.0, 0),
    )


class BrokenSynth:
    """The kernel's own synth gone wrong (what takes a plugin stream's place now that
    no plugin code is on the audio path): a ramped 1 V sine that steps to 99 V after
    ``step_at`` samples, or (``end_level``) rises slowly to it and ends there, at
    ``n_total`` samples, without its ramp down."""

    def __init__(self, step_at=4860, end_level=None, n_total=9600):  # 4860: a crest
        self.k, self.step_at, self.end_level, self.n_total = 0, step_at, end_level, n_total

    def next_block(self, synth, n):
        if self.k >= self.n_total:
            return None
        k = self.k + np.arange(n)
        if self.end_level is not None:  # rises slowly to end_level and stops there
            x = np.minimum(k * 0.01, self.end_level)
        else:
            x = np.sin(2 * np.pi * 200 * k / FS) * np.minimum(1.0, k / 480)
            x = np.where(k >= self.step_at, x * 99.0, x)
        self.k += n
        return x, np.zeros(n)


def broken_stream(table, monkeypatch, broken, peak_v):
    """Play a stream on ``table`` whose synth renders ``broken`` (what the scheduler and
    the gate get block by block); its report."""
    report, synth = table.scheduler.stream(stream_spec(peak_v), "broken")
    monkeypatch.setattr(synth, "next_block", lambda n: broken.next_block(synth, n))
    return report


@pytest.mark.parametrize(
    "peak_v, why",
    [(99.0, "slew"), (30.0, "exceeds its declared peak")],
    ids=["step-within-its-peak", "step-over-its-peak"],
)
def test_stream_stepping_mid_way_is_ramped_down_and_estops(table, monkeypatch, peak_v, why):
    """The per-block checks on a live stream: a step inside the stream's declared peak is
    the gate's slew check; over it, the scheduler's peak check. Either e-stops, and the
    step never reaches the amplifier."""
    report = broken_stream(table, monkeypatch, BrokenSynth(), peak_v)
    report.wait(10)
    assert report.error
    assert table.gate.estopped and why in table.gate.estop_reason, table.gate.estop_reason
    assert table.gate.wait_safe(5)
    assert_within_slew(table)
    rec = table.recording()
    assert np.abs(rec[:, 0]).max() > 0.9, "the stream played before its step"
    assert np.abs(rec[:, 0]).max() < 5.0, "the 99 V step never reached the amp"
    assert rec[-1, 0] == 0.0


def test_stream_ending_high_ramps_down_across_blocks(table, monkeypatch):
    report = broken_stream(table, monkeypatch, BrokenSynth(end_level=80.0, n_total=12000), 99.0)
    report.wait(10)
    assert not report.error, report.error
    rec = table.recording()
    assert np.abs(rec[:, 0]).max() >= 79.0
    assert rec[-1, 0] == 0.0
    assert_within_slew(table)
    assert not table.gate.estopped


# ---------------------------------------------------------------- 2. immutable plans
def test_a_checked_plan_changed_after_play_never_plays_its_old_samples(outputs):
    loud = tone(250, 100.0, 0.05, FS, 0.01)
    plan = OutputPlan(FS, [Segment(loud, np.zeros_like(loud), frozenset({"PA"}))], name="p")
    outputs.play(plan)
    n1 = outputs.recording().shape[0]
    short = np.zeros(480)
    with contextlib.suppress(TypeError):  # segments are a tuple: a changed plan is a new plan
        plan.segments[0] = Segment(short, short, frozenset({"PB"}))
    outputs.play(plan)
    rec = outputs.recording()[n1:]
    pb = [s for s in outputs.relay_log() if s.channel == 2 and s.closed]
    assert not (pb and np.any(rec)), "the first play's 100 V samples went out on PB"


def test_segment_arrays_changed_after_check_do_not_play(outputs):
    x = tone(250, 10.0, 0.05, FS, 0.01)
    seg = Segment(x, np.zeros_like(x), frozenset({"PA"}))
    plan = OutputPlan(FS, (seg,), name="p")
    outputs.play(plan)
    with contextlib.suppress(ValueError):  # read-only
        seg.piezo_v[1000:1500] = 200.0
    outputs.play(plan)
    assert np.abs(outputs.recording()[:, 0]).max() <= 10.0 + 1e-4  # float32 recording


# ------------------------------------------- 3. sources in the scheduler's place
class DCSource(Source):
    def __init__(self, level=50.0, dtype=float):
        self.level, self.dtype = level, dtype

    def next_block(self, n):
        return np.full(n, self.level).astype(self.dtype), np.zeros(n)

    @property
    def idle(self):
        return False

    def abort(self, reason):
        pass


def test_attached_source_stepping_to_dc_is_stopped(table):
    table.set_relays({1})
    table.gate.attach_scheduler(DCSource(50.0))
    wait_until(lambda: table.gate.estopped)
    assert "slew" in table.gate.estop_reason, table.gate.estop_reason
    assert table.gate.wait_safe(5)
    assert np.abs(table.recording()[:, 0]).max() < 1.0, "0 -> 50 V DC never reached the amp"


def test_object_dtype_block_estops_without_killing_the_audio_thread(table):
    table.set_relays({1})
    table.gate.attach_scheduler(DCSource(0.0, dtype=object))
    wait_until(lambda: table.gate.estopped)
    assert "dtype object" in table.gate.estop_reason, table.gate.estop_reason
    assert table.gate.wait_safe(5)
    c0 = table.gate.clock
    table.reset()
    table.gate.attach_scheduler(table.scheduler)
    x = tone(250, 10.0, 0.05, FS, 0.01)
    table.play(OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),)))
    assert table.gate.clock > c0, "the audio thread still runs"


# ---------------------------------------------------------------- 4. a stalled stream
def test_estop_with_a_stalled_stream_opens_relays_only_after_silence(table, monkeypatch):
    """The kernel's synth stalls the audio thread inside ``fill`` (its block may still
    be signal): the e-stop waits for that block and the ramp down after it, then opens
    the relays in silence; it does not wait for the give-up time."""
    stall_s = 0.3
    stalling, stalled_until = threading.Event(), []
    report, synth = table.scheduler.stream(stream_spec(10.0), "stalls")
    real = synth.next_block

    def stalls(n):
        if synth.samples_out >= 2400 and not stalling.is_set():
            stalling.set()
            time.sleep(stall_s)
            stalled_until.append(time.monotonic())
        return real(n)

    monkeypatch.setattr(synth, "next_block", stalls)
    synth.post([1])  # a 10 V burst, playing when the stall comes
    assert stalling.wait(10)
    t0 = time.monotonic()
    table.estop()
    assert time.monotonic() - t0 < stall_s + 0.4, "the e-stop waited for the give-up time"
    assert table.gate.relay_state() == frozenset()
    assert not [e for e in table.gate.events if "without observed silence" in e.message]
    rec = table.recording()
    assert np.abs(rec[:, 0]).max() > 1.0, "the stream was playing"
    guard = table.limits.guard_samples
    opened = [sw for sw in table.relay_log() if not sw.closed]
    assert opened
    for sw in opened:
        assert sw.t_s >= stalled_until[0], "a relay opened while the stalled block was out"
        assert sw.level_v == (0.0, 0.0), sw
        assert not np.any(rec[max(0, sw.clock - guard) : sw.clock]), "signal before opening"


# ---------------------------------------------------------------- 5. relay commands
def test_relay_command_refused_during_estop_never_runs_later(outputs):
    outputs.estop()
    with pytest.raises(SafetyRefusal, match="e-stop"):
        outputs.set_relays({1, 5})
    outputs.reset()
    x = tone(250, 10.0, 0.02, FS, 0.005)
    outputs.play(OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),)))
    time.sleep(0.05)
    assert outputs.relay_state() == frozenset()
    assert not any(s.closed and s.channel == 5 for s in outputs.relay_log())


def test_timed_out_relay_command_is_dropped(outputs):
    x = tone(250, 10.0, 1.0, FS, 0.01)
    report = outputs.play(
        OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),)), wait=False
    )
    with pytest.raises(SafetyRefusal, match="timed out"):
        outputs.set_relays({3}, timeout_s=0.01)
    report.wait(10)
    time.sleep(0.05)
    assert 3 not in outputs.relay_state() and 3 not in outputs.operator_relays()
    assert not any(s.channel == 3 for s in outputs.relay_log())


def test_operator_relays_are_restored_after_a_stimulus(outputs):
    outputs.set_relays({3})
    x = tone(250, 10.0, 0.3, FS, 0.01)
    report = outputs.play(
        OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),)), wait=False
    )
    wait_until(lambda: report.segment_start)
    toggle = outputs.set_relays({3, 6}, wait=False)  # pressed while the stimulus plays
    report.wait(10)
    toggle.wait(10)
    assert outputs.relay_state() == frozenset({3, 6}), "operator's setting restored"
    assert outputs.operator_relays() == frozenset({3, 6})
    assert any(s.channel == 1 and s.closed for s in outputs.relay_log()), "PA was routed"


def test_relay_switching_is_rate_limited(table):
    gate = table.gate
    ok = refused = 0
    t_end = time.monotonic() + 0.5
    while time.monotonic() < t_end:
        try:
            gate.switch_relays(frozenset() if gate.relay_state() else frozenset({7}))
            ok += 1
        except SafetyRefusal as exc:
            refused += "rate" in str(exc) or "switched" in str(exc)
    lim = table.limits
    assert refused > 0
    # the gate's own clock bounds it: at most one switch per interval of samples played
    assert ok <= gate.clock / max(lim.min_switch_interval_samples, 1) + 2


@pytest.mark.parametrize("gap_s", [float("nan"), float("inf"), -1.0, 1e9])
def test_a_plan_gap_is_checked_and_counted(outputs, gap_s):
    x = tone(250, 10.0, 0.05, FS, 0.01)
    seg = Segment(x, np.zeros_like(x), frozenset({"PA"}))
    plan = OutputPlan(FS, (seg, seg), name="gappy", gap_s=gap_s)
    with pytest.raises(SafetyRefusal, match="gap_s|max_plan_s"):
        outputs.play(plan)
    assert not np.any(outputs.recording())


def test_a_switch_answer_from_before_an_estop_is_not_taken_by_the_next_stimulus(table):
    board = table.board
    release = threading.Event()
    orig = board.set

    def slow_set(ch, closed):
        if ch == 1 and closed:
            release.wait(5)  # the relay board takes its time (USB)
        elif closed:
            time.sleep(0.05)
        orig(ch, closed)

    board.set = slow_set
    table.set_relays({1}, wait=False)  # the worker is now inside the switch
    time.sleep(0.05)
    t = threading.Thread(target=table.estop)
    t.start()
    time.sleep(0.05)
    release.set()
    t.join(5)
    assert table.gate.relay_state() == frozenset(), "the e-stop waited and opened it"
    table.reset()
    x = tone(250, 10.0, 0.05, FS, 0.01)
    table.play(OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PB"})),)))
    assert not table.gate.estopped, table.gate.estop_reason
    assert any(s.channel == 2 and s.closed for s in table.relay_log())
