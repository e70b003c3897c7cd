"""Every patch on its own channel: the profile's ``[audio] channels``, the plan check, the
gate's per-channel checks and e-stop ramp, and the twin's five-channel outputs."""

from __future__ import annotations

import dataclasses
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from console.config.profile import PROJECT_PROFILES, load_profile
from console.core.channels import ChannelLayout, layout_problem
from console.core.errors import ProfileError, SafetyRefusal
from console.core.types import PATCHES, OutputPlan, Segment
from console.kernel.client import open_outputs
from console.safety import Limits, SafetyGate, check_plan
from console.safety.block_rules import block_first_problem, block_ok
from console.signals.stream_synth import PulseSpec, StreamSpec
from console.signals.waveforms import ramp_envelope

FS = 48000
FOUR = ("PA", "PB", "PC", "PD", "screen")
SIM_4CH = (PROJECT_PROFILES / "sim-4ch.toml").read_text()


def sine(n: int, amp_v: float, f_hz: float) -> np.ndarray:
    return amp_v * np.sin(2 * np.pi * f_hz * np.arange(n) / FS) * ramp_envelope(n, 480)


# ------------------------------------------------------------------------- layout
@pytest.mark.parametrize(
    ("names", "expect"),
    [
        (["piezo", "screen"], None),
        (list(FOUR), None),
        (["PC", "screen", "PA"], None),
        (["piezo", "screen", "PA"], "either the bus or one channel per patch"),
        (["PA", "PA", "screen"], "'PA' is named twice"),
        (["PA", "PB"], "name the screen's channel"),
        (["PE", "screen"], "unknown channel 'PE'"),
        (["screen"], "no piezo channel"),
    ],
)
def test_layout_problems(names, expect):
    got = layout_problem(names)
    assert got is None if expect is None else expect in got


def test_columns_of_bus_and_per_patch_segments():
    a, c = sine(4800, 40, 200), sine(4800, 20, 330)
    four = ChannelLayout(FOUR)
    cols = four.columns(Segment(a, np.zeros(4800), frozenset({"PB", "PD"})))
    assert [bool(np.any(x)) for x in cols] == [False, True, False, True, False]
    assert cols[1] is a and cols[3] is a
    cols = four.columns(Segment.per_patch({"PA": a, "PC": c}))
    assert cols[0] is a and cols[2] is c and not cols[1].any() and not cols[4].any()
    bus = ChannelLayout()
    with pytest.raises(ValueError, match="drive each patch on its own"):
        bus.columns(Segment.per_patch({"PA": a, "PC": c}))
    with pytest.raises(ValueError, match="has no channel for it"):
        ChannelLayout(("PA", "screen")).columns(Segment.per_patch({"PC": c}))


# ------------------------------------------------------------------------- profile
def test_sim_4ch_loads_with_five_channels_and_no_patch_relays(plugins):
    prof = load_profile("sim-4ch", plugins)
    assert tuple(prof.get("audio.channels")) == FOUR
    assert all(not p["relay_channel"] for p in prof.items("patches").values())
    assert Limits.from_profile(prof).channels == FOUR
    assert load_profile("sim", plugins).get("audio.channels") == ["piezo", "screen"]


@pytest.mark.parametrize(
    ("text", "expect"),
    [
        (
            SIM_4CH.replace('"PA", "PB", "PC", "PD", "screen"', '"PA", "PA", "screen"'),
            ["[audio] channels", "'PA' is named twice"],
        ),
        (
            SIM_4CH.replace('"PA", "PB", "PC", "PD", "screen"', '"piezo", "PA", "screen"'),
            ["[audio] channels", "either the bus"],
        ),
        (
            SIM_4CH.replace('"PA", "PB", "PC", "PD", "screen"', '"piezo", "screen"'),
            ["[patches.PA] has no relay_channel", "set relay_channel"],
        ),
        (
            SIM_4CH.replace('"PA", "PB", "PC", "PD", "screen"', '"PA", "PB", "PC", "screen"'),
            ["[patches.PD] has no relay_channel"],
        ),
    ],
)
def test_bad_channel_profiles_one_line(tmp_path, plugins, text, expect):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ProfileError) as err:
        load_profile(str(path), plugins)
    msg = str(err.value)
    assert "\n" not in msg and "bad.toml" in msg
    for part in expect:
        assert part in msg, (part, msg)


def relayed_4ch(tmp_path: Path) -> Path:
    """sim-4ch with a relay per patch (channels 1..4), as sim.toml wires them."""
    text = SIM_4CH
    for i, p in enumerate(PATCHES, 1):
        text = text.replace(f"[patches.{p}]\n", f"[patches.{p}]\nrelay_channel = {i}\n")
    path = tmp_path / "sim-4ch-relays.toml"
    path.write_text(text)
    return path


# ------------------------------------------------------------------------- plan check
def limits4(**kw) -> Limits:
    base = dict(
        sample_rate_hz=FS,
        piezo_min_v=-100.0,
        piezo_max_v=250.0,
        screen_max_v=100.0,
        piezo_card_v=100.0,
        screen_card_v=100.0,
        rating_vpp=350.0,
        ramp_samples=240,
        max_plan_samples=FS * 10,
        guard_samples=240,
        settle_samples=336,
        estop_timeout_s=0.05,
        channels=FOUR,
    )
    base.update(kw)
    return Limits(**base)


def test_plan_check_is_per_channel():
    lim = limits4()
    n = 4800
    ok = Segment.per_patch({"PA": sine(n, 60, 200), "PC": sine(n, -60, 200)}, label="pair")
    check_plan(OutputPlan(FS, (ok,), name="ok"), lim)
    over = Segment.per_patch({"PA": sine(n, 60, 200), "PC": sine(n, 120, 200)}, label="pair")
    with pytest.raises(SafetyRefusal, match=r"pair\): PC channel .* outside -100..100 V"):
        check_plan(OutputPlan(FS, (over,), name="p"), lim)
    jump = sine(n, 60, 200)
    jump[2000:2100] += 40.0
    bad = Segment.per_patch({"PA": sine(n, 10, 200), "PD": jump})
    with pytest.raises(SafetyRefusal, match="PD channel steps"):
        check_plan(OutputPlan(FS, (bad,), name="p"), lim)
    lost = Segment(sine(n, 10, 200), np.zeros(n), patch_v={"PA": sine(n, 10, 300)})
    with pytest.raises(SafetyRefusal, match="piezo_v reaches no patch"):
        check_plan(OutputPlan(FS, (lost,), name="p"), lim)
    nowhere = Segment.per_patch({"PB": sine(n, 10, 200)})
    with pytest.raises(SafetyRefusal, match="has no channel for it"):
        check_plan(OutputPlan(FS, (nowhere,), name="p"), limits4(channels=("PA", "screen")))
    # the bus still refuses drives that differ, and plays them when equal
    pair = OutputPlan(FS, (ok,), name="pair")
    with pytest.raises(SafetyRefusal, match="drive each patch on its own"):
        check_plan(pair, limits4(channels=("piezo", "screen")))


# ------------------------------------------------------------------------- gate
class Level:
    """An attached source: every channel rises to its own level and holds it."""

    def __init__(self, levels_v: list[float], rise: int = 2000):
        self.levels = np.array(levels_v)
        self.rise, self.k = rise, 0
        self.idle = False

    def next_block(self, n: int):
        k = self.k + np.arange(n)
        self.k += n
        env = np.minimum(1.0, k / self.rise)
        return tuple(env * lv for lv in self.levels)

    def abort(self, reason: str) -> None:
        pass


class Board:
    channels = 8

    def __init__(self):
        self.state = [False] * 8

    def set(self, ch: int, closed: bool) -> None:
        self.state[ch - 1] = closed

    def states(self):
        return tuple(self.state)


def test_estop_ramps_all_five_channels_at_their_slew_limits():
    # small currents: a ramp of many samples, per channel (screen: 200 nF, patches 90 nF)
    lim = limits4(piezo_current_a=0.02, screen_current_a=0.02, relay_current_a=0.02)
    board = Board()
    gate = SafetyGate(lim, board, relay_channels={}, screen_channel=5)
    gate.switch_relays(frozenset({5}))
    out = np.zeros((64, 5), np.float32)
    for _ in range(lim.settle_samples // 64 + 1):
        gate.fill(out)
    levels = [40.0, -30.0, 20.0, -10.0, 25.0]
    gate.attach_scheduler(Level(levels, rise=4000))
    rows = []
    for _ in range(100):
        gate.fill(out)
        rows.append(out.copy())
    assert not gate.estopped, list(gate.events)
    assert np.allclose(gate.level_v, levels)
    gate.estop("test", wait=False)
    for _ in range(200):
        gate.fill(out)
        rows.append(out.copy())
    assert gate.wait_safe(2)
    volts = np.vstack(rows) * np.array([lim.piezo_card_v] * 4 + [lim.screen_card_v])
    after = volts[100 * 64 :]
    steps = lim.column_steps_v(frozenset(PATCHES))
    for k in range(5):
        d = np.abs(np.diff(np.concatenate([[levels[k]], after[:, k]])))
        assert d.max() <= steps[k] * 1.0001 + 1e-6, (k, d.max(), steps[k])
        assert d[1] > 0.5 * steps[k]  # it ramps from the first sample after the e-stop
        zero_at = int(np.flatnonzero(after[:, k] == 0)[0])
        assert zero_at == pytest.approx(abs(levels[k]) / steps[k], abs=2)
        assert not after[zero_at:, k].any()
    assert board.state == [False] * 8


def test_gate_refuses_a_patch_channel_whose_relay_is_open():
    lim = limits4()
    board = Board()
    gate = SafetyGate(lim, board, relay_channels={"PA": 1, "PB": 2}, screen_channel=5)
    assert gate.closed_patches() == {"PC", "PD"}  # no relay: always connected
    out = np.zeros((64, 5), np.float32)
    for _ in range(10):
        gate.fill(out)
    gate.attach_scheduler(Level([0.0, 0.0, 5.0, -5.0, 0.0]))
    for _ in range(20):
        gate.fill(out)
    assert not gate.estopped and out[-1, 2] > 0 and out[-1, 3] < 0
    gate.attach_scheduler(Level([0.0, 5.0, 0.0, 0.0, 0.0]))
    gate.fill(out)
    assert gate.estopped and "PB signal while its patch relay is open" in gate.estop_reason


def test_gate_faults_on_a_block_of_the_wrong_width():
    gate = SafetyGate(limits4(), Board(), relay_channels={}, screen_channel=5)
    gate.attach_scheduler(Level([1.0, 0, 0, 0, 0]))
    gate.fill(np.ones((64, 2), np.float32))  # a two-channel driver on a five-channel profile
    assert gate.estopped and "names 5 channels" in gate.estop_reason
    two = SafetyGate(limits4(), Board(), relay_channels={}, screen_channel=5)

    class Pair(Level):
        def next_block(self, n):
            return np.zeros(n), np.zeros(n)

    two.attach_scheduler(Pair([0.0]))
    out = np.ones((64, 5), np.float32)
    two.fill(out)
    assert two.estopped and "gave 2 channels, expected 5" in two.estop_reason
    assert not out.any()


# ------------------------------------------------------------------------- twin outputs
@pytest.fixture
def outputs4(plugins):
    out = open_outputs(load_profile("sim-4ch", plugins), plugins, fast=True)
    yield out
    out.close()


def test_different_waveforms_on_pa_and_pc_reach_their_channels(outputs4):
    n = 9600
    a, c = sine(n, 60, 180), sine(n, 35, 260)
    r = outputs4.play(OutputPlan(FS, (Segment.per_patch({"PA": a, "PC": c}),), name="pair"))
    rec = outputs4.recording()
    assert rec.shape[1] == 5
    s = r.segment_start[0]
    tol = 1e-5 * 60  # float32 sound-card units
    assert np.abs(rec[s : s + n, 0] - a).max() < tol
    assert np.abs(rec[s : s + n, 2] - c).max() < tol
    assert not rec[:, [1, 3, 4]].any()
    # a bus segment plays its piezo_v on each listed patch's channel
    b = sine(n, 50, 220)
    r = outputs4.play(OutputPlan(FS, (Segment(b, np.zeros(n), frozenset({"PB", "PD"})),)))
    rec = outputs4.recording()
    s = r.segment_start[0]
    assert np.abs(rec[s : s + n, 1] - b).max() < tol
    assert np.abs(rec[s : s + n, 3] - b).max() < tol
    assert not rec[s : s + n, [0, 2, 4]].any()
    assert outputs4.relay_log() == []  # no patch relays on sim-4ch, the screen unused


class Burst:
    """A client's live stream: its parameters (a 20 V, 200 Hz piezo burst of 50 ms on PB
    and PC at each crossing) and, once the kernel opened it, its side to post to."""

    def __init__(self):
        self.spec = StreamSpec(
            sample_rate_hz=FS,
            patches=frozenset({"PB", "PC"}),
            screen=False,
            carrier_max_v=0.0,
            carrier_min_hz=60,
            carrier_max_hz=400,
            start_hz=180,
            glide_ms=10,
            ramp_ms=10,
            pulse=PulseSpec("burst", "piezo", 20.0, 200.0, 50.0, 0),
        )
        self.sink = None

    def bind(self, sink):
        self.sink = sink


def test_streams_play_on_their_patches_channels(outputs4):
    stream = Burst()
    report = outputs4.stream(stream)
    stream.sink.post([1])
    time.sleep(0.1)  # the burst (50 ms) played
    stream.sink.request_stop()
    report.wait(10)
    assert not report.error and report.detents and report.detents[0][0] == 1
    rec = outputs4.recording()
    assert np.abs(rec[:, 1]).max() > 15 and np.array_equal(rec[:, 1], rec[:, 2])
    assert not rec[:, [0, 3, 4]].any()
    assert not outputs4.estopped


def test_relays_on_a_four_channel_profile_switch_in_silence(tmp_path, plugins):
    prof = load_profile(str(relayed_4ch(tmp_path)), plugins)
    n = 4800
    with open_outputs(prof, plugins, fast=True) as out:
        plan = OutputPlan(
            FS, (Segment.per_patch({"PA": sine(n, 30, 200), "PD": sine(n, 30, 250)}),)
        )
        out.play(plan)
        log = out.relay_log()
        assert {(r.channel, r.closed) for r in log} == {
            (1, True),
            (4, True),
            (1, False),
            (4, False),
        }
        assert all(r.level_v == (0.0,) * 5 for r in log)
        # every relay is open again (a signal on a patch whose relay is open is refused)
        assert out.relay_state() == frozenset()


def test_estop_on_sim_4ch_silences_every_channel_and_the_audit_agrees(outputs4):
    from console.benchmarks.safety import fresh_window
    from console.safety.audit import received_problems

    start = fresh_window(outputs4)
    n = FS * 2
    seg = dataclasses.replace(
        Segment.per_patch({p: sine(n, 40 + 10 * i, 150 + 40 * i) for i, p in enumerate(PATCHES)}),
        screen_v=sine(n, 30, 120),
        screen=True,
    )
    report = outputs4.play(OutputPlan(FS, (seg,), name="all"), wait=False)
    stop = threading.Event()

    def estop_soon():
        while not report.segment_start and not stop.is_set():
            stop.wait(0.001)
        stop.wait(0.01)
        outputs4.estop("test")

    th = threading.Thread(target=estop_soon)
    th.start()
    report.done.wait(10)
    stop.set()
    th.join()
    assert outputs4.wait_safe(5)
    rec = outputs4.recording()
    s = report.segment_start[0]
    assert all(np.abs(rec[s:, k]).max() > 5 for k in range(5))  # all five were playing
    assert not rec[-64:].any() and tuple(outputs4.status()["gate"]["level_v"]) == (0.0,) * 5
    problems = received_problems(
        outputs4.limits,
        rec,
        outputs4.relay_log(),
        outputs4.events(),
        start,
        frozenset(PATCHES),
        int(outputs4.status()["latency_samples"]),
    )
    assert not problems, problems


# ------------------------------------------------------------------------- commands
def test_play_writes_a_wav_with_a_channel_per_output(tmp_path):
    import wave

    from console.cli.main import main

    path = tmp_path / "pc.wav"
    assert main(["--profile", "sim-4ch", "play", "sine-PC", "--dry-run", "--out", str(path)]) == 0
    with wave.open(str(path)) as w:
        assert w.getnchannels() == 5
        x = np.frombuffer(w.readframes(w.getnframes()), "<i2").reshape(-1, 5)
    assert np.abs(x[:, 2]).max() > 6000 and not x[:, [0, 1, 3, 4]].any()


def test_haptable_estop_reaches_five_channel_outputs_mid_plan(plugins):
    from console.kernel.shell import estop

    prof = load_profile("sim-4ch", plugins)
    with open_outputs(prof, plugins, fast=False) as out:
        n = FS
        seg = Segment.per_patch({p: sine(n, 30, 200 + 20 * i) for i, p in enumerate(PATCHES)})
        report = out.play(OutputPlan(FS, (seg,), name="all4"), wait=False)
        while not report.segment_start:
            report.done.wait(0.005)
        report.done.wait(0.05)
        everywhere, latched = estop(None, 2.0)  # `haptable estop`, every table
        reached = [r for r in everywhere if r.pid == out.kernel_pid]
        assert reached and reached[0].confirmed, everywhere
        assert out.table.key in {t.key for t in latched}
        st = out.status()["gate"]
        assert tuple(st["level_v"]) == (0.0,) * 5 and st["estopped"] and not st["relays_closed"]
        t_end = time.monotonic() + 2
        while not out.estopped and time.monotonic() < t_end:  # the kernel's event
            time.sleep(0.005)
        assert out.estopped and "haptable estop" in out.estop_reason
        rec = out.recording()
        assert all(np.abs(rec[:, k]).max() > 10 for k in range(4))  # they were all playing
        assert not rec[-out.status()["latency_samples"] :].any()


@pytest.mark.parametrize("layout", [("piezo", "screen"), FOUR])
def test_the_gates_one_pass_check_agrees_with_the_per_channel_one(layout):
    """The block check every block takes (all channels at once) against the per-channel
    check that words the refusal: the same verdict on random blocks near every limit."""
    rng = np.random.default_rng(7)
    lim = limits4(channels=layout, piezo_current_a=0.05, relay_current_a=0.05)
    relays = {"PA": 1, "PB": 2} if layout == FOUR else {p: i for i, p in enumerate(PATCHES, 1)}
    gate = SafetyGate(lim, Board(), relay_channels=relays, screen_channel=5)
    n, agree, refused = 64, 0, 0
    for trial in range(600):
        closed = frozenset(int(c) for c in np.flatnonzero(rng.random(5) < 0.8) + 1)
        relays_now = tuple(i + 1 in closed for i in range(8))
        level = tuple(float(v) for v in rng.uniform(-20, 20, len(layout)) * rng.integers(0, 2))
        clock = int(rng.integers(0, 8 * lim.settle_samples))
        # the state a block is judged on (the sealed gate's is set only by its methods)
        judged = gate._judge_state(relays_now, level, lim.settle_samples, clock)
        steps = judged.steps
        np.testing.assert_array_equal(steps, lim.column_steps_v(judged.patches))
        cols = []
        for k in range(len(layout)):
            walk = level[k] + np.cumsum(rng.uniform(-1, 1, n) * steps[k] * 1.001)
            if rng.random() < 0.5:
                walk = np.zeros(n)
            cols.append(walk)
        k = int(rng.integers(len(layout)))
        fault = rng.integers(6)
        if fault == 1:
            cols[k][rng.integers(n)] = np.nan
        elif fault == 2:
            cols[k] = cols[k] + rng.choice([-1, 1]) * 110.0
        ok = block_ok(cols, judged, gate._rules)
        problem = block_first_problem(cols, judged, gate._rules)
        assert ok == (problem is None), (trial, problem)
        agree += 1
        refused += problem is not None
    assert agree == 600 and 60 < refused < 540  # both verdicts were exercised
