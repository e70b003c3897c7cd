"""The twin sound card: a device buffer of ``[twin_audio] buffer_periods`` blocks, underruns
only when the simulated DAC finds it empty, an e-stop ramps the queued blocks to 0 V at the
slew step, recordings stay sample-exact and relay switches see the level actually at the
amplifiers. (E-stops at random moments and late blocks: test_twin_audio_slew.py.)

The DAC model is driven with a fake clock (``TwinAudioOutput.step(now)``), so these tests
assert what happened, never how long it took.
"""

from __future__ import annotations

import numpy as np
import pytest

from console.core.types import OutputPlan, Segment
from console.safety import GateEvent
from console.signals.waveforms import tone
from plugins.twin.outputs import TwinAudioOutput

FS, BS = 48000, 64
PERIOD_S = BS / FS


class Counter:
    """A gate stand-in: block k holds the sample numbers k*BS .. (k+1)*BS - 1 (scaled)."""

    def __init__(self) -> None:
        self.n = 0
        self.idle = False
        self.listeners: list = []

    def fill(self, out: np.ndarray) -> None:
        k = np.arange(self.n, self.n + out.shape[0], dtype=np.float64)
        out[:, 0] = (k % 1000 + 1) / 1000.0  # never zero
        out[:, 1] = -out[:, 0]
        self.n += out.shape[0]


def twin(profile, periods: int = 3) -> tuple[TwinAudioOutput, Counter]:
    out = TwinAudioOutput(profile, buffer_periods=periods, record_s=1.0)
    out.paced = True
    src = Counter()
    out._source = src  # step() is driven by hand: no thread
    return out, src


def run_until(out: TwinAudioOutput, t_end: float, t: float = 0.0, *, late_s: float = 0.0):
    """Wake the driver whenever it asks (``late_s`` after); returns the clock at the end."""
    while t < t_end:
        wait = out.step(t)
        t += wait + (late_s if wait > 0 else 0.0)
    return t


def expected(n: int) -> np.ndarray:
    k = np.arange(n, dtype=np.float64)
    x = ((k % 1000 + 1) / 1000.0).astype(np.float32)
    return np.column_stack([x, -x])


@pytest.mark.parametrize("periods", [2, 3, 4])
def test_buffer_primes_then_plays_in_real_time_without_underruns(profile, periods):
    out, _ = twin(profile, periods)
    assert out.step(0.0) == 0.0  # priming fills the whole buffer at once
    t = run_until(out, 0.5)
    assert out.underruns == 0
    played = out._played(t)
    # the DAC played half a second, the driver never further ahead than the buffer
    assert abs(played - FS // 2) <= periods * BS
    assert 0 <= out._written - played <= periods * BS
    np.testing.assert_array_equal(out.recording_card(), expected(out._written))
    assert out.status()["latency_s"] == pytest.approx(periods * PERIOD_S)


def test_late_driver_underruns_only_when_the_buffer_runs_dry(profile):
    """Buffer of 3 periods: the driver may be up to 2 periods late (ALSA/PortAudio)."""
    out, _ = twin(profile, 3)
    run_until(out, 0.5, late_s=1.9 * PERIOD_S)
    assert out.underruns == 0, "late by less than the buffered blocks: no underrun"
    out2, _ = twin(profile, 3)
    run_until(out2, 0.5, late_s=2.5 * PERIOD_S)
    assert out2.underruns > 0, "late by more than the buffered blocks: the DAC starved"
    assert out2.status()["underrun_s"] > 0
    # the recording holds what the gate handed over, gapless (the silence is not in it)
    np.testing.assert_array_equal(out2.recording_card(), expected(out2._written))


def test_one_long_stall_counts_one_underrun_and_the_gap(profile):
    out, _ = twin(profile, 3)
    t = run_until(out, 0.2)
    t += 0.050  # the driver thread stalled 50 ms
    run_until(out, t + 0.2, t)
    assert out.underruns == 1
    # the DAC had up to 3 blocks queued when the stall began
    assert 0.050 - 3 * PERIOD_S <= out.underrun_s <= 0.050


def test_a_stall_in_silence_is_an_underrun_nobody_hears(profile):
    out, src = twin(profile, 3)
    t = run_until(out, 0.2)
    t = run_until(out, t + 0.2, t + 0.050)  # stalled while a tone played
    assert (out.underruns, out.underruns_audible) == (1, 1)
    src.fill = lambda block: block.fill(0.0)  # the gate has nothing to play
    t = run_until(out, t + 0.2, t)
    run_until(out, t + 0.2, t + 0.050)  # stalled in silence
    assert (out.underruns, out.underruns_audible) == (2, 1)
    assert out.status()["underruns_audible"] == 1


def test_estop_ramps_the_queued_blocks_from_the_sample_playing(profile):
    """The queued blocks from the sample playing at the e-stop become a ramp from its level
    to 0 V at the event's slew step (no step at the cut), then silence; the block under way
    is replaced too."""
    out, src = twin(profile, 4)
    t = run_until(out, 0.1)
    out.step(t)  # the buffer is full again
    played, written = out._played(t), out._written
    assert written - played > BS, "blocks are queued"
    step_v = (5.0, 4.0)
    out._on_gate_event(GateEvent(t, written, "estop", "operator e-stop", ramp_step_v=step_v))
    src.n = 10**6  # whatever the next fill holds (a block under way at the e-stop) is dropped
    out.step(t + PERIOD_S)
    rec = out.recording_card()
    np.testing.assert_array_equal(rec[:played], expected(played), "the past is untouched")
    level = expected(played)[-1].astype(np.float64)
    k = np.arange(1, rec.shape[0] - played + 1)[:, None]
    ramp = np.sign(level) * np.maximum(np.abs(level) - k * np.array(step_v) / out._to_v, 0.0)
    np.testing.assert_allclose(rec[played:], ramp, atol=1e-6)
    volts = out.recording_v()[played - 1 :]
    assert np.all(np.abs(np.diff(volts, axis=0)) <= np.array(step_v) * (1 + 1e-6) + 1e-4)
    assert not np.any(rec[-BS:]), "silent once the ramp is over"
    assert out._probe(t + 10 * PERIOD_S)[1] == (0.0, 0.0)


def test_other_gate_events_keep_the_buffer(profile):
    out, _ = twin(profile, 3)
    t = run_until(out, 0.05)
    out._on_gate_event(GateEvent(t, 0, "switch", "relays closed: [1]"))
    np.testing.assert_array_equal(out.recording_card(), expected(out._written))


def test_paced_plan_is_sample_exact_and_switches_only_in_played_silence(profile, plugins):
    from console.kernel.client import open_outputs

    sig = tone(250, 10, 0.3, FS)
    plan = OutputPlan(
        FS,
        (
            Segment(sig, np.zeros_like(sig), frozenset({"PA"})),
            Segment(0.5 * sig, np.zeros_like(sig), frozenset({"PB"})),
        ),
        gap_s=0.01,
    )
    with open_outputs(profile, plugins, fast=False) as out:
        periods = out.status()["audio"]["buffer_periods"]
        assert out.status()["latency_samples"] == periods * out.status()["audio"]["block_size"]
        report = out.play(plan, timeout_s=30)
        rec = out.recording()
        for k, seg in enumerate(plan.segments):
            a = report.segment_start[k]
            np.testing.assert_allclose(rec[a : a + seg.n_samples, 0], seg.piezo_v, atol=1e-3)
        lim = out.limits
        switches = out.relay_log()
        assert len(switches) >= 4
        for sw in switches:
            assert sw.level_v == (0.0, 0.0), sw
            near = rec[max(0, sw.clock - lim.guard_samples) : sw.clock + lim.settle_samples]
            assert not np.any(near), f"signal at the amplifiers near switch {sw}"


def test_paced_estop_cuts_within_the_buffer(profile, plugins):
    from console.kernel.client import open_outputs

    sig = tone(250, 10, 3.0, FS)
    plan = OutputPlan(FS, (Segment(sig, np.zeros_like(sig), frozenset({"PA"})),))
    with open_outputs(profile, plugins, fast=False) as out:
        bs = out.status()["audio"]["block_size"]
        periods = out.status()["audio"]["buffer_periods"]
        report = out.play(plan, wait=False)
        while (
            not report.segment_start
            or out.status()["gate"]["clock"] < report.segment_start[0] + FS // 5
        ):
            report.done.wait(0.01)
        out.estop("test e-stop")
        stop = [e for e in out.events() if e.kind == "estop"][0].clock
        rec = out.recording()
        step_v = out.limits.column_steps_v(frozenset({"PA"}))
        assert np.all(np.abs(np.diff(rec, axis=0)) <= step_v * 1.0005 + 1e-4), "no step"
        ramp = int(np.ceil(max(out.limits.piezo_range()) / step_v[0]))
        assert not np.any(rec[stop + ramp :]), "the queued blocks ramp down, nothing after"
        quiet = np.flatnonzero(np.any(rec[:stop] != 0, axis=1))
        last_signal = int(quiet[-1]) + 1 if quiet.size else 0
        if last_signal < stop - periods * bs - bs:  # silent before the queued blocks:
            # only an underrun may explain it (a loaded machine's DAC found the buffer
            # empty, held the last sample, then ramped to 0 V), never the e-stop's cut
            audio = out.status()["audio"]
            hold = int(audio["underrun_hold_s"] * FS) + ramp + bs
            gaps = [c for c, *_ in audio["underrun_last"] if last_signal - hold <= c <= stop]
            assert gaps, f"only the queued blocks were cut: silent from {last_signal} to {stop}"
        assert out.relay_log()[-1].level_v == (0.0, 0.0)


class Ramp:
    """A gate stand-in handing ``levels`` (one per block, held), then silence."""

    def __init__(self, levels: list[float]) -> None:
        self.levels = list(levels)
        self.idle = False
        self.listeners: list = []

    def fill(self, out: np.ndarray) -> None:
        out[:] = self.levels.pop(0) if self.levels else 0.0


def fast_twin(profile, src) -> TwinAudioOutput:
    out = TwinAudioOutput(profile, record_s=1.0)
    out.paced = False
    out._source = src  # step() is driven by hand: no thread
    return out


def test_estop_drops_the_gate_ramp_down_until_it_ends_in_silence(profile):
    """After the cut the gate still ramps down from the level it last handed: the driver
    ramps on its own from the sample playing, and the gate's ramp (from a level the driver
    has left behind) is dropped until the gate hands a block that ends in silence."""
    src = Ramp([0.3, 0.3, 0.2, 0.1, 0.0, 0.4])  # block 5: a new signal after the ramp
    out = fast_twin(profile, src)
    out.step(0.0)
    out.step(0.0)
    step_v = (3.0, 3.0)  # volts per sample: 0.03 of the piezo channel's 100 V full scale
    out._on_gate_event(GateEvent(0.0, 2 * BS, "estop", "operator e-stop", ramp_step_v=step_v))
    for _ in range(4):
        out.step(0.0)
    rec = out.recording_card()[:, 0]
    assert np.all(rec[: 2 * BS] == np.float32(0.3)), "what played before the cut stays"
    ramp = np.maximum(0.3 - 0.03 * np.arange(1, 3 * BS + 1), 0.0)
    np.testing.assert_allclose(rec[2 * BS : 5 * BS], ramp, atol=1e-6)
    assert np.all(rec[5 * BS :] == np.float32(0.4)), "the cut ends with the gate's silence"


def test_an_estop_in_silence_drops_nothing_later(profile):
    """An e-stop while the gate hands silence and no block is under way cuts nothing: the
    gate only hands silence after it, and what it plays after a reset is not dropped."""
    src = Ramp([0.3, 0.0])
    out = fast_twin(profile, src)
    out.step(0.0)
    out.step(0.0)
    out._on_gate_event(GateEvent(0.0, 2 * BS, "estop", "operator e-stop"))
    src.levels = [0.2, 0.2]  # after a reset, from silence (a ramp in the real gate)
    out.step(0.0)
    out.step(0.0)
    rec = out.recording_card()[:, 0]
    assert np.all(rec[2 * BS :] == np.float32(0.2)), "a block after the e-stop was dropped"


def test_a_stopped_output_leaves_the_relays_to_the_live_one_of_the_same_profile(profile, plugins):
    """Two outputs of one profile file (a profile changed in memory keeps its path): after
    the second stops, the first one's relay switches carry the first one's clock again
    (they carried the stopped output's, so a closed loop read the wrong samples)."""
    import dataclasses

    from console.kernel.client import open_outputs

    first = open_outputs(profile, plugins, fast=True)
    try:
        x = tone(250, 5.0, 0.05, FS, 0.01)
        plan = OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),), name="p")
        first.play(plan)
        other = dataclasses.replace(profile, data=dict(profile.data))  # same path
        second = open_outputs(other, plugins, fast=True)
        second.play(plan)
        second.play(plan)
        second.close()
        report = first.play(plan)
        switches = [r for r in first.relay_log() if r.closed]
        assert switches[-1].clock <= report.segment_start[0]
        assert switches[-1].clock >= report.segment_start[0] - 2 * FS  # its own clock
        assert first.status()["audio"]["blocks"] * BS >= report.segment_end[0]
    finally:
        first.close()


def test_an_underrun_says_where_the_late_thread_s_time_went(profile):
    """The paced thread's fill waits 60 ms on a lock another thread holds (as it would for
    the interpreter lock): the underrun is counted with origin ``process`` (``host`` if
    the hypervisor happened to take the machine's CPUs then), never ``unknown`` on Linux."""
    import threading
    import time
    from pathlib import Path

    out = TwinAudioOutput(profile, buffer_periods=3, record_s=1.0)
    out.paced = True
    held = threading.Lock()
    src = Counter()
    plain_fill = src.fill

    def fill(block):
        with held:  # another thread has it for a while once
            plain_fill(block)

    src.fill = fill
    out.start(src)
    try:
        time.sleep(0.1)
        with held:
            time.sleep(0.06)
        time.sleep(0.1)
    finally:
        out.stop()
    st = out.status()
    assert st["underruns"] >= 1
    assert sum(st["underruns_by_origin"].values()) == st["underruns"]
    if Path("/proc/thread-self/schedstat").exists():
        assert st["underruns_by_origin"]["unknown"] == 0
        assert st["underruns_by_origin"]["process"] + st["underruns_by_origin"]["host"] >= 1
        assert st["underrun_last"][-1][4] in ("process", "host", "scheduler")


def test_a_recording_read_while_it_plays_is_what_was_played(profile):
    """Copies taken while the paced thread writes (the bulk outside the driver's lock)
    hold exactly the rows the recording holds after, none garbled or shifted."""
    import time

    out = TwinAudioOutput(profile, buffer_periods=3, record_s=3.0)
    out.paced = True
    out.start(Counter())
    copies = []
    try:
        t_end = time.monotonic() + 1.0
        while time.monotonic() < t_end:
            copies.append(out.recording_card())
            time.sleep(0.01)
    finally:
        out.stop()
    final = out.recording_card()
    assert len(copies) > 20 and final.shape[0] > max(c.shape[0] for c in copies) > 0
    for rec in copies:
        np.testing.assert_array_equal(rec, final[: rec.shape[0]])


def test_rows_the_ring_overwrites_during_a_copy_are_dropped_and_since_reads_the_rest(profile):
    """While the first chunk is copied the writer wraps the ring over the oldest rows:
    the copy starts at the oldest row still kept, its rows are the gate's in order."""
    out = TwinAudioOutput(profile, buffer_periods=3, record_s=0.5)
    out.paced = True
    src = Counter()
    out._source = src
    t = run_until(out, 0.4)
    plain_view = out._ring_view
    advanced = []

    def view_while_writing(a, b):
        if not advanced:  # the driver runs 0.3 s meanwhile: the ring wraps past ``a``
            advanced.append(run_until(out, t + 0.3, t))
        return plain_view(a, b)

    out._ring_view = view_while_writing
    first, rec = out._snapshot()
    assert advanced and first == out._kept_from > 0
    k = np.arange(first, first + rec.shape[0], dtype=np.float64)
    np.testing.assert_array_equal(rec[:, 0], ((k % 1000 + 1) / 1000.0).astype(np.float32))
    out._ring_view = plain_view
    whole = out.recording_card()
    np.testing.assert_array_equal(out.recording_card(since=100), whole[100:])
    assert out.recording_card(since=whole.shape[0] + 5).shape == (0, whole.shape[1])
