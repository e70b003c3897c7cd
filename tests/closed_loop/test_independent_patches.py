"""Independent patches in closed loop: a plan with different waveforms on PA and PC played
through the safety gate on the five-channel twin (profiles/sim-4ch.toml), read back from
the twin's recording, and put through the plate twin. References: the superposition of
the single-patch responses (linearity, each computed alone), and the twin's FRF per patch
in steady state (frequency domain, another code path), amplitude and phase."""

from __future__ import annotations

import numpy as np
import pytest

from console.config.profile import load_profile
from console.core.types import OutputPlan, Segment
from console.kernel.client import open_outputs
from plugins.twin.plate import closed_loop as cl
from plugins.twin.plate.loop_play import recording_with_offset, relay_channels_of

FS = 48000
PTS = np.array([[401.73, 223.645], [100.0, 100.0], [700.0, 400.0], [580.0, 150.0]])
F_A, F_C = 247.0, 389.0  # PA and PC play different tones
A_V, C_V = 60.0, 40.0


def ramped(f_hz: float, amp_v: float, n: int, ramp: int = 4800) -> np.ndarray:
    k = np.arange(n)
    env = np.minimum(1.0, np.minimum(k, n - 1 - k) / ramp)
    return amp_v * env * np.sin(2 * np.pi * f_hz * k / FS)


@pytest.fixture(scope="module")
def played(loop_plugins):
    """The plan, the recorded drive and weights on the five-channel twin, and its twin."""
    prof = load_profile("sim-4ch", loop_plugins)
    n = 3 * FS
    a, c = ramped(F_A, A_V, n), ramped(F_C, C_V, n)
    plan = OutputPlan(FS, (Segment.per_patch({"PA": a, "PC": c}, label="PA+PC"),), name="pair")
    with open_outputs(prof, loop_plugins, fast=True) as out:
        report = out.play(plan)
        rec, clock0 = recording_with_offset(out)
        start, stop = report.segment_start[0], report.segment_end[0]
        v, w = cl.drive_from_recording(
            rec,
            out.relay_log(),
            relay_channels_of(prof),
            start,
            stop,
            clock0,
            prof.get("audio.channels"),
        )
    return plan, a, c, v, w, cl.twin_of(prof)


def test_the_recording_holds_each_patch_on_its_own_channel(played):
    plan, a, c, v, w, _ = played
    assert v.shape == (a.size, 4)
    assert np.abs(v[:, 0] - a).max() < 1e-5 * A_V
    assert np.abs(v[:, 2] - c).max() < 1e-5 * C_V
    assert not v[:, [1, 3]].any()
    assert np.all(w == 1.0)  # no patch relays on sim-4ch: always connected
    v_plan, w_plan, spans = cl.drive_from_plan(plan)
    assert v_plan.shape == v.shape and np.abs(v_plan - v).max() < 1e-5 * A_V
    assert spans == [(0, a.size, frozenset({"PA", "PC"}))]


def test_displacement_is_the_superposition_of_single_patch_responses(played):
    _, a, c, v, w, twin = played
    both = cl.displacement_at(twin, v, w, PTS, FS)
    alone_a = cl.displacement_at(twin, v[:, 0], [(0, a.size, {"PA"})], PTS, FS)
    alone_c = cl.displacement_at(twin, v[:, 2], [(0, c.size, {"PC"})], PTS, FS)
    scale = np.abs(both).max()
    assert scale > 0.1  # um: the plate moves
    assert np.abs(both - (alone_a + alone_c)).max() < 1e-9 * scale
    # and it is not what either patch does alone (the test can tell them apart)
    assert np.abs(both - alone_a).max() > 0.05 * scale
    assert np.abs(both - alone_c).max() > 0.05 * scale


def test_steady_state_matches_each_patchs_frf_with_its_phase(played):
    _, a, _, v, w, twin = played
    x = cl.displacement_at(twin, v, w, PTS, FS)
    # a flat second in the middle: after the 0.1 s ramp and >1 s of settling
    k = np.arange(int(1.2 * FS), int(2.2 * FS))
    t = k / FS
    for f_hz, amp, patch in ((F_A, A_V, "PA"), (F_C, C_V, "PC")):
        basis = np.column_stack(
            [
                np.cos(2 * np.pi * F_A * t),
                np.sin(2 * np.pi * F_A * t),
                np.cos(2 * np.pi * F_C * t),
                np.sin(2 * np.pi * F_C * t),
            ]
        )
        ab = np.linalg.lstsq(basis, x[:, k].T, rcond=None)[0]
        i = 0 if f_hz == F_A else 2
        phasor = ab[i] - 1j * ab[i + 1]  # amp sin(wt) = Re(-amp j e^{jwt})
        h = twin.frf_um_per_v(PTS[:, 0], PTS[:, 1], [f_hz], (patch,))[0, :, 0]
        assert np.abs(phasor - h * (-1j * amp)).max() < 2e-3 * np.abs(h * amp).max(), patch


def test_drive_from_a_recording_with_some_patch_relays():
    from types import SimpleNamespace as R

    names = ("PB", "PA", "screen")  # PC and PD have no channel; PA has a relay, PB none
    rec = np.zeros((1000, 3))
    rec[:, 0] = np.arange(1000)  # PB
    rec[:, 1] = -np.arange(1000)  # PA
    log = [R(clock=100, channel=1, closed=True), R(clock=600, channel=1, closed=False)]
    v, w = cl.drive_from_recording(rec[50:], log, {"PA": 1}, 80, 900, 50, names)
    assert v.shape == (820, 4)
    assert v[0, 1] == 80 and v[0, 0] == -80 and not v[:, 2:].any()
    assert np.all(w[:, 1] == 1.0)  # PB: no relay, always connected
    assert not w[:20, 0].any() and w[20:520, 0].all() and not w[520:, 0].any()  # PA's relay
    assert not w[:, 2:].any()
    with pytest.raises(ValueError, match="recording has 3 channels"):
        cl.drive_from_recording(rec, log, {"PA": 1}, channels=("piezo", "screen"))


def test_drive_from_a_plan_mixing_bus_and_per_patch_segments():
    n = 2400
    a, b = ramped(200.0, 10.0, n, 240), ramped(300.0, 20.0, n, 240)
    plan = OutputPlan(
        FS,
        (
            Segment(a, np.zeros(n), frozenset({"PB", "PD"})),
            Segment.per_patch({"PA": b, "PC": -b}),
        ),
        gap_s=0.01,
    )
    v, w, spans = cl.drive_from_plan(plan)
    gap = int(0.01 * FS)
    assert v.shape == (2 * n + gap, 4) and w.shape == v.shape
    assert np.array_equal(v[:n, 1], a) and np.array_equal(v[:n, 3], a) and not v[:n, [0, 2]].any()
    assert not v[n : n + gap].any() and not w[n : n + gap].any()
    assert np.array_equal(v[n + gap :, 0], b) and np.array_equal(v[n + gap :, 2], -b)
    assert spans[1] == (n + gap, 2 * n + gap, frozenset({"PA", "PC"}))
    # the same bus plan without per-patch segments keeps the bus drive (n,)
    bus, _, _ = cl.drive_from_plan(OutputPlan(FS, plan.segments[:1]))
    assert bus.shape == (n,)
