"""The sealed safety gate (audit: "code holding the gate could change its state and get
past it"): each way the audit got past the gate on the twin, reproduced on a gate driven
block by block (no driver thread) and on the twin's outputs, and refused now; the limits
are deep-immutable; a block the one-pass check fails is refused whatever the message
search finds."""

from __future__ import annotations

import dataclasses
import pickle
import time
from collections.abc import Callable
from types import MappingProxyType

import numpy as np
import pytest

from console.core.errors import SafetyRefusal
from console.core.types import PATCHES, OutputPlan, Segment
from console.safety import GENERIC_REFUSAL, GateEvent, Limits, SafetyGate, Source, check_plan
from console.safety import gate as gate_module
from console.safety.block_rules import block_first_problem, block_ok
from console.signals.waveforms import ramp_envelope

FS = 48000
BLOCK = 64
RELAYS = {"PA": 1, "PB": 2, "PC": 3, "PD": 4}
SCREEN = 5
FOUR = ("PA", "PB", "PC", "PD", "screen")


def sim_limits(**kw) -> Limits:
    """The sim profile's limits (bus and screen, a relay per patch, 90 nF patches)."""
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
        patch_capacitance_f={p: 90e-9 for p in PATCHES},
        patch_relay=dict(RELAYS),
        min_switch_interval_samples=960,
    )
    base.update(kw)
    return Limits(**base)


class MemoryBoard:
    channels = 8

    def __init__(self) -> None:
        self.closed = [False] * self.channels

    def set(self, channel: int, closed: bool) -> None:
        self.closed[channel - 1] = closed

    def states(self) -> list[bool]:
        return list(self.closed)


class Wave(Source):
    """The scheduler's stand-in: ``wave(k)`` (sample indices -> one array per channel),
    block after block, until the e-stop aborts it."""

    def __init__(self, wave: Callable[[np.ndarray], tuple[np.ndarray, ...]]) -> None:
        self.wave, self.k, self.stopped = wave, 0, False

    def next_block(self, n: int):
        if self.stopped:
            return None
        k = self.k + np.arange(n)
        self.k += n
        return self.wave(k)

    @property
    def idle(self) -> bool:
        return self.stopped

    def abort(self, reason: str) -> None:
        self.stopped = True


def tone(amp_v: float, f_hz: float = 250.0, rise: int = 480) -> Callable:
    """A sine on the bus rising over ``rise`` samples; the screen silent."""

    def wave(k):
        x = amp_v * np.sin(2 * np.pi * f_hz * k / FS) * np.minimum(1.0, k / rise)
        return x, np.zeros(k.size)

    return wave


def bursts(amp_v: float, blocks: int | None = None) -> Callable:
    """A half-sine of ``amp_v`` in every block, each ending at exactly 0 V (for
    ``blocks`` blocks, then nothing)."""

    def wave(k):
        if blocks is not None and k[0] >= blocks * BLOCK:
            return None
        j = k % BLOCK
        x = np.where(j == BLOCK - 1, 0.0, amp_v * np.sin(np.pi * j / (BLOCK - 1)))
        return x, np.zeros(k.size)

    return wave


def refused(change: Callable[[], object]) -> bool:
    """Try one of the audit's changes; True when it raised (the gate refused it)."""
    try:
        change()
    except (AttributeError, TypeError):
        return True
    return False


class Rig:
    """A gate on an in-memory relay board, its blocks pulled here and kept as volts."""

    def __init__(self, limits: Limits | None = None, relay_channels=None, screen_channel=SCREEN):
        self.limits = limits or sim_limits()
        self.board = MemoryBoard()
        self.gate = SafetyGate(
            self.limits,
            self.board,
            relay_channels=dict(RELAYS) if relay_channels is None else relay_channels,
            screen_channel=screen_channel,
            latency_samples=BLOCK,
        )
        self.card = np.array(
            [
                self.limits.screen_card_v if c == "screen" else self.limits.piezo_card_v
                for c in self.limits.channels
            ]
        )
        self.rows: list[np.ndarray] = []

    def pump(self, blocks: int = 1) -> None:
        out = np.zeros((BLOCK, len(self.limits.channels)), np.float32)
        for _ in range(blocks):
            self.gate.fill(out)
            self.rows.append(out.astype(np.float64) * self.card)

    def close(self, relays: set[int]) -> None:
        """Switch to ``relays`` and pull silence until the settle time has passed."""
        self.gate.switch_relays(frozenset(relays))
        for _ in range(100):
            self.pump()
            if self.gate.settled():
                return
        raise AssertionError("the relays never settled")

    def recording(self) -> np.ndarray:
        return np.vstack(self.rows) if self.rows else np.zeros((0, len(self.limits.channels)))

    def max_steps(self) -> np.ndarray:
        rec = self.recording()
        return np.abs(np.diff(rec, axis=0, prepend=0.0)).max(axis=0)

    def finish(self) -> None:
        """Pull blocks until an e-stop has opened the relays."""
        for _ in range(200):
            if self.gate.wait_safe(0):
                break
            self.pump()
            time.sleep(0.001)
        assert self.gate.wait_safe(2)


# ---------------------------------------------------------------- sealed: assignment raises
STATE_NAMES = [
    "limits",
    "relay_channels",
    "screen_channel",
    "latency_samples",
    "clock",
    "level_v",
    "relays",
    "events",
    "layout",
    "estop_reason",
    "scope",
    "estopped",
    "idle",
]


@pytest.mark.parametrize("name", STATE_NAMES)
def test_every_state_name_is_read_only(name):
    gate = Rig().gate
    before = getattr(gate, name)
    with pytest.raises(AttributeError, match="sealed"):
        setattr(gate, name, before)
    with pytest.raises(AttributeError, match="sealed"):
        delattr(gate, name)
    assert getattr(gate, name) == before


def test_no_attribute_can_be_added_or_replaced_not_even_a_private_one():
    gate = Rig().gate
    for name, value in [
        ("listeners", []),
        ("attach", print),
        ("_s", None),
        ("_limits", sim_limits(piezo_card_v=300.0)),
        ("_relay_channels", {}),
        ("_ranges", (np.full(2, -1e9), np.full(2, 1e9))),
        ("_hand", lambda out, cols: None),
        ("__class__", object),
    ]:
        with pytest.raises((AttributeError, TypeError)):
            setattr(gate, name, value)
    assert type(gate) is SafetyGate and not hasattr(gate, "__dict__")


def test_what_the_gate_hands_out_cannot_be_changed():
    rig = Rig()
    gate = rig.gate
    rig.close({1})
    assert isinstance(gate.relays, tuple) and isinstance(gate.level_v, tuple)
    assert isinstance(gate.events, tuple) and gate.events[-1].kind == "switch"
    with pytest.raises(AttributeError):
        gate.events.append(GateEvent(0.0, 0, "reset", "forged"))  # a snapshot, a tuple
    assert isinstance(gate.relay_channels, MappingProxyType)
    with pytest.raises(TypeError):
        gate.relay_channels["PA"] = 9
    with pytest.raises(dataclasses.FrozenInstanceError):
        gate.layout.names = ("piezo",)  # type: ignore[misc]
    with pytest.raises(AttributeError, match="read-only"):
        gate.scope._tap = None  # type: ignore[misc]
    assert not hasattr(gate.scope, "write")
    with pytest.raises(dataclasses.FrozenInstanceError):
        gate.events[-1].kind = "reset"  # type: ignore[misc]
    with pytest.raises(ValueError):
        gate._rules.hi[0] = 1e9  # the checks' own arrays are read-only too
    with pytest.raises(ValueError):
        gate._steps(gate.relays)[1][0] = 1e9


def test_attached_sources_and_the_listener_list_are_gone():
    gate = Rig().gate
    assert not hasattr(gate, "attach")
    assert not hasattr(gate, "listeners")


# ------------------------------------------------------------------ 1. replaced limits
def test_the_gates_limits_cannot_be_replaced():
    rig = Rig()
    gate, lim = rig.gate, rig.limits
    loose = dataclasses.replace(lim, piezo_max_v=250.0, piezo_card_v=300.0)
    with pytest.raises(AttributeError, match="sealed"):
        gate.limits = loose
    assert gate.limits is lim
    # what the audit then played: a 150 V tone, refused at the gate's own limits
    rig.close({1})
    gate.attach_scheduler(Wave(tone(150.0, 50.0, rise=2400)))
    rig.pump(60)
    rig.finish()
    assert gate.estopped and "outside -100..100 V" in gate.estop_reason
    assert np.abs(rig.recording()[:, 0]).max() <= 100.0 + 1e-3


def test_a_plan_passed_by_loosened_limits_still_meets_the_gates():
    """``scheduler.limits`` replaced: the scheduler is not the gate, and its plan check
    with the loosened limits passes a 150 V plan. The gate keeps its own: it refuses the
    first block over them and e-stops; the amplifiers never get past 100 V."""
    rig = Rig()
    gate = rig.gate
    loose = dataclasses.replace(
        rig.limits, piezo_min_v=-250.0, piezo_max_v=250.0, piezo_card_v=300.0
    )
    n = 24000
    x = 150.0 * np.sin(2 * np.pi * 50 * np.arange(n) / FS) * ramp_envelope(n, 4800)
    plan = OutputPlan(FS, (Segment(x, np.zeros(n), frozenset({"PA"})),), name="150V")
    check_plan(plan, loose)  # what a scheduler holding the loosened limits accepts
    with pytest.raises(SafetyRefusal, match="outside -100..100 V"):
        check_plan(plan, rig.limits)
    sealed = refused(lambda: setattr(gate, "limits", loose))
    rig.close({1})
    gate.attach_scheduler(Wave(lambda k: (x[k % n], np.zeros(k.size))))
    rig.pump(n // BLOCK)
    rig.finish()
    assert np.abs(rig.recording()[:, 0]).max() <= 100.0 + 1e-3, "150 V reached the amp"
    assert gate.estopped and "outside -100..100 V" in gate.estop_reason
    assert sealed and gate.limits is rig.limits


def test_a_failed_fast_check_refuses_the_block_whatever_the_message_search_finds(monkeypatch):
    """The audit's fail-open path: the one-pass check refuses a block, the per-rule search
    (here made to find nothing) names no rule. The block must not play: the e-stop trips
    with the generic message and the driver gets the ramp down."""
    monkeypatch.setattr(gate_module, "block_first_problem", lambda cols, judged, rules: None)
    rig = Rig()
    gate = rig.gate
    rig.close({1})

    def stepping(k):  # a 20 V tone that steps by 60 V in one sample from sample 1500
        x = 20.0 * np.sin(2 * np.pi * 250 * k / FS) * np.minimum(1.0, k / 480)
        return np.where(k >= 1500, x + 60.0, x), np.zeros(k.size)

    gate.attach_scheduler(Wave(stepping))
    rig.pump(40)
    rig.finish()
    assert gate.estopped and GENERIC_REFUSAL in gate.estop_reason
    faults = [e for e in gate.events if e.kind == "fault"]
    assert faults and faults[0].message == GENERIC_REFUSAL
    step = rig.limits.max_step_v("piezo", frozenset({"PA"}))
    assert rig.max_steps()[0] <= step * 1.0001 + 1e-6, "the 60 V step reached the amp"
    assert np.abs(rig.recording()[:, 0]).max() < 25.0
    assert gate.relay_state() == frozenset()


def test_both_checks_judge_one_snapshot_of_the_state(monkeypatch):
    """The fast check and the message search see the same state object, taken once."""
    seen: list[tuple[str, object]] = []
    ok, first = gate_module.block_ok, gate_module.block_first_problem

    def spy_ok(cols, judged, rules):
        seen.append(("ok", judged))
        return ok(cols, judged, rules)

    def spy_first(cols, judged, rules):
        seen.append(("first", judged))
        return first(cols, judged, rules)

    monkeypatch.setattr(gate_module, "block_ok", spy_ok)
    monkeypatch.setattr(gate_module, "block_first_problem", spy_first)
    rig = Rig()
    rig.close({1})
    rig.gate.attach_scheduler(Wave(lambda k: (np.full(k.size, 60.0), np.zeros(k.size))))
    rig.pump(1)
    assert [w for w, _ in seen] == ["ok", "first"]
    judged = seen[0][1]
    assert seen[1][1] is judged
    assert judged.relays == (True,) + (False,) * 7 and judged.level_v == (0.0, 0.0)
    assert rig.gate.estopped and "steps 60.00 V" in rig.gate.estop_reason
    rig.finish()


# ------------------------------------------------------------ 2. the limits' inner dicts
def test_the_limits_inner_mappings_cannot_be_changed():
    lim = sim_limits()
    with pytest.raises(TypeError):
        lim.patch_capacitance_f["PA"] = 1e-15
    with pytest.raises(TypeError):
        del lim.patch_capacitance_f["PA"]
    with pytest.raises(TypeError):
        lim.patch_relay["PA"] = 8
    with pytest.raises(AttributeError):
        lim.patch_relay.clear()  # type: ignore[attr-defined]
    with pytest.raises(dataclasses.FrozenInstanceError):
        lim.piezo_max_v = 250.0  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        lim.patch_capacitance_f = {"PA": 1e-15}  # type: ignore[misc]
    assert isinstance(lim.channels, tuple)
    assert lim.patch_capacitance_f["PA"] == pytest.approx(90e-9)
    assert lim.max_step_v("piezo", frozenset({"PA"})) == pytest.approx(0.1 / 90e-9 / FS)


def test_a_tiny_capacitance_cannot_let_a_90_v_step_through():
    """The audit set ``patch_capacitance_f["PA"] = 1e-15`` under a live gate and got a
    90 V one-sample step; now the item assignment raises and the step is refused."""
    rig = Rig()
    caps = rig.gate.limits.patch_capacitance_f
    sealed = refused(lambda: caps.__setitem__("PA", 1e-15))  # type: ignore[attr-defined]
    rig.close({1})
    rig.gate.attach_scheduler(Wave(lambda k: (np.full(k.size, 90.0), np.zeros(k.size))))
    rig.pump(10)
    rig.finish()
    assert np.abs(rig.recording()[:, 0]).max() == 0.0, "the 90 V step reached the amp"
    assert rig.gate.estopped and "steps 90.00 V" in rig.gate.estop_reason
    assert sealed


def test_limits_keep_private_copies_and_still_replace_pickle_and_read():
    caps = {p: 90e-9 for p in PATCHES}
    relays = dict(RELAYS)
    channels = ["piezo", "screen"]
    lim = sim_limits(patch_capacitance_f=caps, patch_relay=relays, channels=channels)
    caps["PA"], relays["PA"] = 1e-15, 8
    channels.append("PA")
    assert lim.patch_capacitance_f["PA"] == pytest.approx(90e-9) and lim.patch_relay["PA"] == 1
    assert lim.channels == ("piezo", "screen")
    loose = dataclasses.replace(lim, piezo_max_v=1.0)
    assert loose is not lim and loose.patch_relay == lim.patch_relay
    assert isinstance(loose.patch_relay, MappingProxyType)
    back = pickle.loads(pickle.dumps(lim))
    assert back == lim and isinstance(back.patch_capacitance_f, MappingProxyType)
    assert dict(lim.patch_relay) == RELAYS and sorted(lim.patch_capacitance_f) == list(PATCHES)


def test_limits_from_the_profile_are_deep_immutable(profile):
    lim = Limits.from_profile(profile)
    assert isinstance(lim.patch_capacitance_f, MappingProxyType)
    assert isinstance(lim.patch_relay, MappingProxyType)
    assert isinstance(lim.channels, tuple)
    with pytest.raises(TypeError):
        lim.patch_capacitance_f["PA"] = 1e-15
    assert lim.patch_relay["PA"] == 1


# ------------------------------------------------------------------ 3. a shrunk relay map
def test_the_relay_map_cannot_be_shrunk():
    """The audit shrank ``gate.relay_channels`` with every patch relay closed: the gate
    took PA alone as connected and let 20 V per sample through against the 11.6 V its
    four patches allow. The map is read-only and the steps are refused."""
    given = dict(RELAYS)
    rig = Rig(relay_channels=given)
    gate = rig.gate
    rig.close({1, 2, 3, 4})
    sealed = [refused(lambda p=p: gate.relay_channels.pop(p)) for p in ("PB", "PC", "PD")]
    sealed.append(refused(lambda: setattr(gate, "relay_channels", {"PA": 1})))
    given.clear()  # the caller's dict is not the gate's
    limit = rig.limits.max_step_v("piezo", frozenset(PATCHES))
    gate.attach_scheduler(Wave(lambda k: (np.minimum(20.0 * (k + 1), 80.0), np.zeros(k.size))))
    rig.pump(10)
    rig.finish()
    assert rig.max_steps()[0] <= limit * 1.0001 + 1e-6, "20 V per sample reached the amp"
    assert gate.estopped and "slew limit" in gate.estop_reason
    assert all(sealed) and dict(gate.relay_channels) == RELAYS


# ---------------------------------------------------------------------- 4. a forged level
def test_the_level_cannot_be_forged():
    """``gate.level_v = (60, 0)`` made the slew check start from 60 V: 0 -> 60 V in one
    sample at the amplifier."""
    rig = Rig()
    gate = rig.gate
    rig.close({1})
    sealed = refused(lambda: setattr(gate, "level_v", (60.0, 0.0)))
    gate.attach_scheduler(Wave(lambda k: (np.full(k.size, 60.0), np.zeros(k.size))))
    rig.pump(10)
    rig.finish()
    assert np.abs(rig.recording()[:, 0]).max() == 0.0, "0 -> 60 V reached the amp"
    assert gate.estopped and "steps 60.00 V" in gate.estop_reason
    assert sealed


# ---------------------------------------------------------------------- 5. a moved clock
def test_the_clock_cannot_be_moved_to_switch_under_a_tone():
    """``gate.clock += 10**6`` made the guard gap look passed: relay 1 opened under an
    80 V tone. The clock is read-only and the switch is refused."""
    rig = Rig()
    gate = rig.gate
    rig.close({1})
    gate.attach_scheduler(Wave(bursts(80.0)))
    rig.pump(20)
    assert gate.level_v == (0.0, 0.0) and not gate.estopped  # each block ends at 0 V
    clock = gate.clock
    sealed = refused(lambda: setattr(gate, "clock", gate.clock + 10**6))
    with pytest.raises(SafetyRefusal, match="silent"):
        gate.switch_relays(frozenset())
    assert gate.relay_state() == frozenset({1}) and rig.board.closed[0]
    assert sealed and gate.clock == clock
    gate.estop("test", wait=False)
    rig.finish()


# ------------------------------------------------------------ 6. an unset screen channel
def test_the_screen_channel_cannot_be_unset():
    """``gate.screen_channel = None`` dropped the screen relay check: 50 V on the screen
    channel with its relay open."""
    rig = Rig()
    gate = rig.gate
    rig.close({1})  # the screen relay (5) stays open
    sealed = refused(lambda: setattr(gate, "screen_channel", None))
    gate.attach_scheduler(Wave(lambda k: (np.zeros(k.size), 50.0 * np.minimum(1.0, k / 2000))))
    rig.pump(40)
    rig.finish()
    assert np.abs(rig.recording()[:, 1]).max() == 0.0, "screen signal with its relay open"
    assert gate.estopped and "screen relay is open" in gate.estop_reason
    assert sealed and gate.screen_channel == SCREEN


# ------------------------------------------------------------------- latency, listeners
def test_the_device_latency_is_set_once_never_lowered_and_only_in_silence():
    rig = Rig()
    gate = rig.gate
    assert gate.latency_samples == BLOCK
    with pytest.raises(SafetyRefusal, match="raised"):
        gate.set_device_latency(BLOCK - 1)
    with pytest.raises(ValueError):
        gate.set_device_latency(-1)
    rig.close({1})
    gate.attach_scheduler(Wave(tone(20.0)))
    rig.pump(5)
    with pytest.raises(SafetyRefusal, match="nothing plays"):
        gate.set_device_latency(4 * BLOCK)
    gate.estop("test", wait=False)
    rig.finish()
    gate.set_device_latency(4 * BLOCK)
    assert gate.latency_samples == 4 * BLOCK
    with pytest.raises(SafetyRefusal, match="already set"):
        gate.set_device_latency(8 * BLOCK)
    assert gate.latency_samples == 4 * BLOCK


def test_the_switch_rules_take_the_device_latency():
    rig = Rig()
    gate = rig.gate
    gate.set_device_latency(4 * BLOCK)
    rig.close({1})
    gate.attach_scheduler(Wave(bursts(20.0, blocks=5)))
    rig.pump(10)  # 5 blocks of bursts, then 320 samples of silence
    assert gate.quiet_samples() == 5 * BLOCK
    # enough for the guard gap and one block of latency (304), not for 240 + 256
    with pytest.raises(SafetyRefusal, match="silent for 320 samples, need 496"):
        gate.switch_relays(frozenset())
    rig.pump(3)
    gate.switch_relays(frozenset())
    assert gate.relay_state() == frozenset()


def test_listeners_are_added_and_removed_through_methods():
    rig = Rig()
    gate = rig.gate
    got: list[GateEvent] = []

    def broken(ev):
        raise RuntimeError("a listener failing never breaks the gate")

    gate.add_listener(got.append)
    gate.add_listener(got.append)  # once is enough
    gate.add_listener(broken)
    rig.close({1})
    assert [e.kind for e in got] == ["switch"]
    gate.remove_listener(got.append)
    gate.remove_listener(got.append)  # not there any more: nothing happens
    gate.estop("test", wait=False)
    rig.finish()
    assert [e.kind for e in got] == ["switch"]
    assert gate.relay_state() == frozenset()


# --------------------------------------------------------------------- the ramp-down step
def test_estop_shutdown_and_fault_events_carry_the_ramp_step_per_channel():
    rig = Rig()
    gate = rig.gate
    lim = rig.limits
    assert gate.ramp_steps_v() == pytest.approx(tuple(lim.column_steps_v(frozenset())))
    rig.close({1, 2, 3, 4})
    pall = tuple(float(s) for s in lim.column_steps_v(frozenset(PATCHES)))
    assert gate.ramp_steps_v() == pytest.approx(pall) and len(pall) == 2
    gate.attach_scheduler(Wave(lambda k: (np.minimum(0.05 * k, 60.0), np.zeros(k.size))))
    rig.pump(30)
    level = gate.level_v[0]
    assert level == 60.0
    gate.estop("operator", wait=False)
    rig.pump(1)
    stop = [e for e in gate.events if e.kind == "estop"][-1]
    assert stop.ramp_step_v == pytest.approx(pall)
    first = rig.recording()[-BLOCK, 0]  # the ramp down starts one step below the level
    assert abs(first) == pytest.approx(max(abs(level) - pall[0], 0.0), abs=1e-3)
    rig.finish()
    # the switch that closed them and the e-stop's opening: no ramp step on either
    assert [e.ramp_step_v for e in gate.events if e.kind == "switch"] == [(), ()]
    gate.reset()
    assert gate.events[-1].kind == "reset" and gate.events[-1].ramp_step_v == ()
    gate.estop("closing", quiet=True, wait=False)
    shutdown = gate.events[-1]
    assert shutdown.kind == "shutdown"
    assert shutdown.ramp_step_v == pytest.approx(tuple(lim.column_steps_v(frozenset())))
    rig.finish()
    faulty = Rig()
    faulty.close({1})
    faulty.gate.attach_scheduler(Wave(lambda k: (np.full(k.size, np.nan), np.zeros(k.size))))
    faulty.pump(1)
    # (the e-stop's relay opening, on its own thread, may have added its switch event)
    fault, stop = [e for e in faulty.gate.events if e.kind != "switch"][-2:]
    pa = tuple(float(s) for s in lim.column_steps_v(frozenset({"PA"})))
    assert fault.kind == "fault" and fault.ramp_step_v == pytest.approx(pa)
    assert stop.kind == "estop" and stop.ramp_step_v == pytest.approx(pa) and not stop.cut
    faulty.finish()


def test_the_ramp_step_has_one_entry_per_sound_card_channel():
    lim = sim_limits(channels=FOUR, patch_relay={})
    gate = SafetyGate(lim, MemoryBoard(), relay_channels={}, screen_channel=SCREEN)
    steps = gate.ramp_steps_v()
    assert len(steps) == 5 and steps == pytest.approx(tuple(lim.column_steps_v(frozenset(PATCHES))))


# ------------------------------------------------------ the two checks agree on one snapshot
@pytest.mark.parametrize("layout", [("piezo", "screen"), FOUR])
def test_the_one_pass_check_and_the_message_search_agree_on_a_snapshot(layout):
    """The block check every block takes (all channels at once) against the per-channel
    search that words the refusal, on the same judged state: the same verdict on random
    blocks near every limit (the gate's state is never assigned: snapshots are built)."""
    rng = np.random.default_rng(7)
    lim = sim_limits(channels=layout, piezo_current_a=0.05, relay_current_a=0.05, patch_relay={})
    relays = {"PA": 1, "PB": 2} if layout == FOUR else {p: i for i, p in enumerate(PATCHES, 1)}
    gate = SafetyGate(lim, MemoryBoard(), relay_channels=relays, screen_channel=SCREEN)
    n, refused = 64, 0
    for trial in range(600):
        closed = frozenset(int(c) for c in np.flatnonzero(rng.random(5) < 0.8) + 1)
        state = tuple(i + 1 in closed for i in range(8))
        level = tuple(float(v) for v in rng.uniform(-20, 20, len(layout)) * rng.integers(0, 2))
        clock = int(rng.integers(0, 8 * lim.settle_samples))
        judged = gate._judge_state(state, level, lim.settle_samples, clock)
        steps = judged.steps
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
        assert gate._block_problem(cols, judged) == problem
        refused += problem is not None
    assert 60 < refused < 540  # both verdicts were exercised
