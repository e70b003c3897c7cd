"""The twin sound card never steps beyond the slew limit, whatever the driver meets: an
operator's e-stop at any moment ramps at the driver, and a late block (an underrun) holds
the last sample, ramps it to 0 V after the hold and slew-follows back when blocks resume.

The DAC is driven with a fake clock (``TwinAudioOutput.step(now)``; the gate's fill is
timed with ``fill_clock``), so these tests assert what happened, never how long it took.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from console.core.types import PATCHES
from console.safety import GateEvent, Limits
from plugins.twin.outputs import TwinAudioOutput

FS, BS = 48000, 64
PERIOD_S = BS / FS
TOL = 1e-4  # volts: float32 card units at 100 V full scale round to ~1e-5 V


class Clock:
    """The fake time both the DAC (``step(now)``) and the fill timing read."""

    def __init__(self) -> None:
        self.t = 0.0

    def now(self) -> float:
        return self.t


class ToneGate:
    """A gate stand-in in card units: a loud tone on every channel until its e-stop, then
    (like the gate) a ramp from the level it last handed at the slew step, then silence.
    ``hook(gate)`` runs inside the next fill; ``slow_s`` makes one fill take that long."""

    def __init__(self, to_v: np.ndarray, steps_v: np.ndarray, clock: Clock | None = None):
        self.to_v = to_v.astype(np.float64)
        self.steps_v = np.asarray(steps_v, dtype=np.float64)
        self.amp = np.array([95.0, 80.0]) / self.to_v  # volts: near the piezo / screen limits
        self.n = 0
        self.idle = False
        self.listeners: list[Callable] = []
        self.estopped = False
        self.level = np.zeros(2)
        self.clock = clock
        self.hook: Callable[[ToneGate], None] | None = None
        self.after_hook: Callable[[ToneGate], None] | None = None
        self.slow_s = 0.0
        self.handed: list[np.ndarray] = []  # every block, as handed to the driver

    def tone(self, a: int, b: int) -> np.ndarray:
        k = np.arange(a, b, dtype=np.float64)[:, None]
        return (self.amp * np.sin(2 * np.pi * 250.0 * k / FS + np.array([0.0, 1.0]))).astype(
            np.float32
        ) * np.minimum(1.0, k / 480)  # ramped in from 0 V

    def ramp_steps_v(self) -> tuple[float, ...]:
        return tuple(self.steps_v)

    def fill(self, out: np.ndarray) -> None:
        if self.hook is not None:
            hook, self.hook = self.hook, None
            hook(self)
        n = out.shape[0]
        if self.estopped:
            k = np.arange(1, n + 1)[:, None]
            step = self.steps_v / self.to_v
            mag = np.maximum(np.abs(self.level) - step * k, 0.0)
            out[:] = np.sign(self.level) * mag
        else:
            out[:] = self.tone(self.n, self.n + n)
        self.level = out[-1].astype(np.float64)
        self.handed.append(out.copy())
        self.n += n
        if self.clock is not None and self.slow_s:
            self.clock.t += self.slow_s
            self.slow_s = 0.0
        if self.after_hook is not None:
            hook, self.after_hook = self.after_hook, None
            hook(self)

    def estop(self, t: float) -> GateEvent:
        self.estopped = True
        ev = GateEvent(t, self.n, "estop", "operator", True, ramp_step_v=tuple(self.steps_v))
        for fn in list(self.listeners):
            fn(ev)
        return ev


def steps_pa(profile) -> np.ndarray:
    return Limits.from_profile(profile).column_steps_v(frozenset({"PA"}))


def tone_twin(
    profile, periods: int = 3, *, paced: bool = True, clock: Clock | None = None
) -> tuple[TwinAudioOutput, ToneGate]:
    out = TwinAudioOutput(profile, buffer_periods=periods, record_s=1.0)
    out.paced = paced
    src = ToneGate(out._to_v, steps_pa(profile), clock)
    out._source = src  # step() is driven by hand: no thread
    src.listeners.append(out._on_gate_event)
    if clock is not None:
        out.fill_clock = clock.now
    return out, src


def run(
    out: TwinAudioOutput,
    clock: Clock,
    t_end: float,
    *,
    stall_at: float = -1.0,
    stall_s: float = 0.0,
) -> None:
    """Wake the driver whenever it asks until ``t_end``; once past ``stall_at`` it comes
    back ``stall_s`` late (one stall)."""
    while clock.t < t_end:
        wait = out.step(clock.t)
        clock.t += wait
        if stall_s and clock.t >= stall_at:
            clock.t += stall_s
            stall_s = 0.0


def assert_within_slew(volts: np.ndarray, steps_v: np.ndarray, what: str) -> None:
    d = np.abs(np.diff(np.vstack([np.zeros((1, volts.shape[1])), volts]), axis=0))
    worst = d.max(axis=0)
    assert np.all(worst <= steps_v * (1 + 1e-6) + TOL), f"{what}: steps {worst} > {steps_v}"


# ------------------------------------------------------------------ e-stop at the driver
@pytest.mark.parametrize("paced", [True, False], ids=["paced", "fast"])
@pytest.mark.parametrize("seed", range(12))
def test_an_estop_at_any_moment_under_a_loud_tone_ramps_within_the_step(profile, paced, seed):
    """Wherever the e-stop lands (between fills, inside a fill before the gate reads its
    flag, or after it filled a loud block), the amplifiers never step beyond the slew
    limit: the recording ramps from the sample playing at the e-stop down to 0 V."""
    rng = np.random.default_rng(seed)
    clock = Clock()
    out, src = tone_twin(profile, int(rng.integers(2, 5)), paced=paced, clock=clock)
    steps_v = src.steps_v
    landing = ("between", "in_fill", "after_fill")[seed % 3]
    t_e = float(rng.uniform(0.015, 0.04))
    at: list[int] = []  # the sample playing at the e-stop

    def estop(gate: ToneGate) -> None:
        at.append(out._played(clock.t))
        gate.estop(clock.t)

    if paced:
        while clock.t < t_e:
            clock.t += out.step(clock.t)
        if landing == "between":
            estop(src)
        elif landing == "in_fill":
            src.hook = estop
        else:
            src.after_hook = estop
        run(out, clock, t_e + 0.02)
    else:
        for _ in range(int(t_e * FS) // BS):
            out.step(0.0)
        if landing == "between":
            estop(src)
        elif landing == "in_fill":
            src.hook = estop
        else:
            src.after_hook = estop
        for _ in range(6):
            out.step(0.0)
    assert at, "the e-stop never landed"
    rec = out.recording_v()
    assert_within_slew(rec, steps_v, f"e-stop {landing} at sample {at[0]}")
    assert out.underruns == 0
    np.testing.assert_array_equal(out.dac_output_v(), rec)
    p = at[0]
    np.testing.assert_allclose(rec[:p], src.tone(0, p) * src.to_v, atol=TOL)
    mag = np.abs(rec[max(p - 1, 0) :])
    assert np.all(np.diff(mag, axis=0) <= TOL), "from the e-stop on the level only falls"
    ramp = int(np.ceil(np.max(src.amp * src.to_v / steps_v)))
    assert not np.any(rec[p + ramp :]), "silent once the driver's ramp is over"


def test_the_estop_ramp_step_falls_back_to_the_source_then_the_profile(profile):
    """An event without ``ramp_step_v`` ramps at the source's ``ramp_steps_v()``; without
    that, at the profile's slowest slew limit (every patch connected)."""
    slowest = Limits.from_profile(profile).column_steps_v(frozenset(PATCHES))
    for asks, want in ((True, np.array([7.0, 6.0])), (False, slowest)):
        out, src = tone_twin(profile, paced=False)
        src.steps_v = np.array([7.0, 6.0])
        if not asks:
            src.ramp_steps_v = None  # a source that cannot say
        for _ in range(20):
            out.step(0.0)
        level = out.recording_v()[-1]
        assert np.all(np.abs(level) > 3 * want), "loud enough for a few ramp steps"
        out._on_gate_event(GateEvent(0.0, src.n, "estop", "operator"))  # no ramp_step_v
        src.estopped = True
        out.step(0.0)
        rec = out.recording_v()[-BS - 1 :]
        np.testing.assert_allclose(np.abs(np.diff(rec[:3], axis=0)), [want, want], atol=TOL)


def test_a_faults_estop_is_not_cut_the_gates_ramp_plays(profile):
    """A fault's e-stop (not ``cut``) leaves the output alone: the gate's own ramp to 0 V
    at the slew limit plays out as handed."""
    out, src = tone_twin(profile, paced=False)
    for _ in range(20):
        out.step(0.0)
    n, steps = out._written, tuple(src.steps_v)
    out._on_gate_event(GateEvent(0.0, n, "fault", "x", False, steps))
    out._on_gate_event(GateEvent(0.0, n, "estop", "fault: x", False, steps))
    src.estopped = True
    out.step(0.0)
    np.testing.assert_array_equal(out.recording_card(), np.concatenate(src.handed))
    assert not np.any(out.recording_card()[-1]), "the gate's ramp reached 0 V"


# ------------------------------------------------------------------ late blocks
def test_a_late_block_holds_then_ramps_then_slew_follows_back(profile):
    """The driver thread stalls 20 ms under a loud tone: the DAC holds the last sample one
    block, ramps it to 0 V at the slew step, and when blocks come back slew-follows the
    tone until it has caught up: no step beyond the limit in what was really played."""
    clock = Clock()
    out, src = tone_twin(profile, 3, clock=clock)
    run(out, clock, 0.08, stall_at=0.04, stall_s=0.020)
    st = out.status()
    assert st["underruns"] == 1 and st["underruns_audible"] == 1
    assert st["underruns_by_cause"] == {"late_wakeup": 1, "slow_fill": 0}
    (u,) = out.underrun_log
    assert u.cause == "late_wakeup" and u.audible and u.ramped
    # the DAC had up to 2 blocks left when the thread stalled at a wakeup
    assert 0.020 * FS - 2 * BS - 1 <= u.samples <= 0.020 * FS
    assert st["underrun_s"] == pytest.approx(u.samples / FS, abs=1e-4)
    rec, dac = out.recording_v(), out.dac_output_v()
    assert dac.shape[0] == rec.shape[0] + u.samples
    assert_within_slew(dac, src.steps_v, "the DAC across the gap and the resume")
    gap = dac[u.clock : u.clock + u.samples]
    np.testing.assert_allclose(gap[: out.hold_samples], np.tile(u.level_v, (BS, 1)), atol=TOL)
    np.testing.assert_allclose(rec[u.clock - 1], u.level_v, atol=TOL)
    assert not np.any(gap[-1]), "ramped to 0 V in a long gap"
    # the recording stays indexed by the gate's clock: the tone before the gap, the
    # slew-followed resume, then the tone again once caught up
    tone = src.tone(0, rec.shape[0]) * src.to_v
    np.testing.assert_allclose(rec[: u.clock], tone[: u.clock], atol=TOL)
    ramp = int(np.ceil(np.max(src.amp * src.to_v / src.steps_v)))
    np.testing.assert_allclose(rec[u.clock + ramp :], tone[u.clock + ramp :], atol=TOL)
    assert np.any(np.abs(rec[u.clock : u.clock + ramp] - tone[u.clock : u.clock + ramp]) > 1)


def test_a_short_late_block_is_held_flat(profile):
    """A gap shorter than the hold (one block) is bridged at the last sample: no ramp."""
    clock = Clock()
    out, src = tone_twin(profile, 3, clock=clock)
    run(out, clock, 0.06, stall_at=0.03, stall_s=2.5 * PERIOD_S)  # 0.5 period dry
    (u,) = out.underrun_log
    assert 0 < u.samples <= out.hold_samples and not u.ramped
    dac = out.dac_output_v()
    np.testing.assert_allclose(
        dac[u.clock : u.clock + u.samples], np.tile(u.level_v, (u.samples, 1)), atol=TOL
    )
    assert_within_slew(dac, src.steps_v, "a short gap")


def test_a_slow_fill_is_counted_as_its_cause(profile):
    """The gate's fill itself takes longer than the buffer's slack: ``slow_fill``."""
    clock = Clock()
    out, src = tone_twin(profile, 3, clock=clock)
    run(out, clock, 0.03)
    src.slow_s = 12 * PERIOD_S  # the slack is 2 periods
    run(out, clock, 0.08)
    st = out.status()
    assert st["underruns_by_cause"] == {"late_wakeup": 0, "slow_fill": 1}
    (u,) = out.underrun_log
    assert u.cause == "slow_fill" and u.ramped
    assert_within_slew(out.dac_output_v(), src.steps_v, "a slow fill")


def test_an_underrun_in_silence_counts_but_nobody_hears_it(profile):
    clock = Clock()
    out, src = tone_twin(profile, 3, clock=clock)
    src.amp = np.zeros(2)  # the gate has nothing to play
    run(out, clock, 0.08, stall_at=0.04, stall_s=0.020)
    st = out.status()
    assert (st["underruns"], st["underruns_audible"]) == (1, 0)
    assert st["underruns_by_cause"]["late_wakeup"] == 1
    (u,) = out.underrun_log
    assert not u.audible and not u.ramped and u.level_v == (0.0, 0.0)
    assert not np.any(out.dac_output_v())


def test_the_relays_see_the_level_the_dac_puts_out_in_a_gap(profile):
    """During a gap the switch level is the held sample, then the ramp, then 0 V."""
    clock = Clock()
    out, src = tone_twin(profile, 3)
    run(out, clock, 0.04)
    t_out = out._t0 + (out._written - out._s0) / FS  # the DAC runs dry then
    held = tuple(float(v) for v in out.recording_v()[-1])
    assert any(abs(v) > 10 for v in held), "a loud sample is held"
    clock_at, level = out._probe(t_out + 0.5 * PERIOD_S)
    assert clock_at == out._written
    np.testing.assert_allclose(level, held, atol=TOL)
    assert out._probe(t_out + 0.02)[1] == (0.0, 0.0), "ramped to 0 V"


@pytest.mark.parametrize("when", ["running_dry", "re_priming"])
def test_an_estop_in_a_gap_ramps_from_the_level_the_dac_holds(profile, when):
    """An operator's e-stop while the DAC is in a gap (the thread late, or refilling the
    buffer after it noticed): the level only falls from the gap on (no climb back to the
    signal queued before the e-stop), within the slew limit, to silence."""
    clock = Clock()
    out, src = tone_twin(profile, 3, clock=clock)
    run(out, clock, 0.04)
    t_out = out._t0 + (out._written - out._s0) / FS
    clock.t = t_out + 1.5 * PERIOD_S  # the driver thread is late: the DAC ramps down
    if when == "running_dry":
        src.estop(clock.t)
    else:  # inside the second fill of the re-priming: one block is queued, not playing
        src.hook = lambda gate: setattr(gate, "hook", lambda g: g.estop(clock.t))
    run(out, clock, clock.t + 0.03)
    assert src.estopped
    (u,) = out.underrun_log
    dac = out.dac_output_v()
    assert_within_slew(dac, src.steps_v, "an e-stop in a gap")
    mag = np.abs(dac[u.clock - 1 :])
    assert np.all(np.diff(mag, axis=0) <= TOL), "the level only falls after the gap began"
    assert not np.any(dac[-BS:])


def test_fast_forward_has_no_buffer_and_no_underruns(profile):
    out, src = tone_twin(profile, 3, paced=False)
    for _ in range(50):
        out.step(1e6)  # whatever the time: a block counts as played when handed over
    st = out.status()
    assert st["underruns"] == 0 and st["buffer_periods"] == 1 and not out.underrun_log
    np.testing.assert_array_equal(out.dac_output_v(), out.recording_v())
