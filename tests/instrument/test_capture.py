"""Duplex audio on the twin: a plan through the gate, the inputs it moved, a roving map.

One fast-forward kernel for the module (the sim profile in 1024-sample blocks, the
sensor without mass, the default sensor noise)."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from scipy import signal

from console.core.errors import SafetyRefusal
from console.plugin_api import OutputPlan, Segment, load_map
from console.plugin_api.runtime import capture, move_sensor, open_outputs, read_inputs
from plugins.twin.plate.model import build_twin, params_from_profile
from plugins.vibrotactile.roving import RovingSettings, chirp_v
from plugins.vibrotactile.roving_run import RovingRun

SENSOR_MM = (281.73, 163.645)
NOISE = 2e-4  # m/s^2/sqrt(Hz), the twin's default accelerometer noise


@pytest.fixture(scope="module")
def duplex():
    from console.config.plugins import load_plugins
    from console.config.profile import load_profile

    pm = load_plugins()
    prof = load_profile("sim", pm)
    data = {
        **prof.data,
        "audio": {**prof.data["audio"], "block_size": 1024},
        "twin_inputs": {"sensor_mass_g": 0.0, "input_noise_v_rms": 0.0},
    }
    prof = dataclasses.replace(prof, data=data)
    out = open_outputs(prof, pm, fast=True)
    yield prof, out
    out.close()


def _plan(volts: np.ndarray, fs: int, patches=frozenset({"PA"})) -> OutputPlan:
    return OutputPlan(fs, (Segment(volts, np.zeros_like(volts), patches, False, "t"),), "t", 0.0)


def _modal_accel(twin, x_mm, y_mm, volts, fs):
    """Independent: each mode a 2nd-order recursion (bilinear, pre-warped to the mode)
    driven by the patch volts, summed at the sensor, plus the static residual's
    acceleration by central differences."""
    phi = twin.modes.shapes(np.array([x_mm / 1e3]), np.array([y_mm / 1e3]))[0]
    z = twin.params.damping_ratio
    acc = np.zeros(volts.size)
    for r, w in enumerate(twin.modes.omega_rad_s):
        wp = 2 * fs * math.tan(w / (2 * fs))  # pre-warped: the pole lands where it is
        b, a = signal.bilinear([phi[r] * twin.q[r, 0], 0, 0], [1, 2 * z * wp, wp**2], fs)
        acc += signal.lfilter(b, a, volts)
    if twin.residual_coeffs is not None:
        from plugins.twin.plate.model import _eval_coeffs

        res = _eval_coeffs(
            twin, twin.residual_coeffs[:1], np.array([x_mm / 1e3]), np.array([y_mm / 1e3])
        )
        acc += float(res[0, 0]) * np.gradient(np.gradient(volts)) * fs**2
    return acc


def test_the_sensor_input_is_the_plate_model_response_to_what_the_dac_played(duplex):
    prof, out = duplex
    fs = out.limits.sample_rate_hz
    move_sensor(out, *SENSOR_MM)
    s = RovingSettings(level_v=20.0, sweep_s=0.5, tail_s=0.4)
    x = np.concatenate([chirp_v(s, fs), np.zeros(int(s.tail_s * fs))])
    cap = capture(out, _plan(x, fs))
    played = out.recording()[cap.clock : cap.clock + cap.card.shape[0], 0]  # the gate's output
    assert np.allclose(played, x, atol=1e-3)  # what was played is the plan, ramps and all
    delay = int(prof.get("twin_inputs.delay_samples") or 45)
    twin = build_twin(params_from_profile(prof))
    ref = np.zeros_like(played)
    ref[delay:] = _modal_accel(twin, *SENSOR_MM, played, fs)[: played.size - delay]
    got = cap.physical("accelerometer")
    diff = got - ref
    # what is left is the sensor's noise, at its documented level (within 10 %)
    sigma = NOISE * math.sqrt(fs / 2)
    assert np.std(diff) == pytest.approx(sigma, rel=0.10)
    assert np.max(np.abs(ref)) > 50 * sigma
    # the loopback is the played output, delayed
    lb = cap.physical("loopback")
    card_v = float(prof.get("audio.full_scale_v"))
    gain = float(prof.get("amplifiers.piezo_gain"))
    assert np.allclose(lb[delay:], played[:-delay] / gain, atol=card_v * 1e-5)


def test_an_over_limit_excitation_is_refused_and_nothing_plays(duplex):
    prof, out = duplex
    fs = out.limits.sample_rate_hz
    before = out.status()["audio"]["blocks"]
    s = RovingSettings(level_v=100.0, sweep_s=0.2, tail_s=0.0)
    hot = chirp_v(s, fs) * 3.0  # 300 V peak: over the patches' limits
    with pytest.raises(SafetyRefusal) as e:
        capture(out, _plan(hot, fs))
    assert "\n" not in str(e.value) and str(e.value)
    assert out.status()["audio"]["blocks"] == before


def test_bad_input_requests_are_one_line_each(duplex):
    prof, out = duplex
    with pytest.raises(SafetyRefusal, match=r"'a'\.\.'b' = 10\.\.5") as e:
        read_inputs(out, 10, 5)
    assert "\n" not in str(e.value)
    with pytest.raises(SafetyRefusal, match=r"sensor at \(900, 10\) mm: outside") as e:
        move_sensor(out, 900, 10)
    assert "\n" not in str(e.value)


def test_a_3_point_roving_map_matches_the_true_frfs_where_coherent(duplex, tmp_path):
    prof, out = duplex
    pts = np.array([[41.73, 43.645], [341.73, 223.645], [701.73, 403.645]])
    s = RovingSettings(level_v=20.0, repeats=3, sweep_s=1.0, tail_s=0.6)
    exc = ("PA", "PALL")
    path = tmp_path / "roving.npz"

    def place(n, x, y):
        move_sensor(out, x, y)

    run = RovingRun(out, path, pts, s, sensor={"kind": "accelerometer"}, excitations=exc)
    got = run.run(place)
    m = load_map(path, require_all=False)
    assert m.excitations == exc and m.points.size == 3
    note = json.loads(m.provenance["note"])
    assert note["sensor"] == {"kind": "accelerometer"}
    coh = np.load(tmp_path / "roving.npz.parts" / "coherence.npz")["coherence"]
    true = build_twin(params_from_profile(prof)).frf_um_per_v(pts[:, 0], pts[:, 1], m.freq_hz, exc)
    err = np.abs(20 * np.log10(np.abs(m.frf_um_per_v) / np.abs(true)))
    good = coh >= 0.9
    assert good.mean() > 0.8
    assert np.mean(err[good] <= 1.0) >= 0.95
    assert np.median(err[good]) < 0.3
    # resumable: run again, nothing is measured again; other settings are refused
    again = RovingRun(out, path, pts, s, sensor={"kind": "accelerometer"}, excitations=exc)
    assert again.run(place)["points_measured_now"] == 0 and got["points_measured_now"] == 3
    with pytest.raises(Exception, match="other settings"):
        RovingRun(out, path, pts, dataclasses.replace(s, repeats=2), sensor={}, excitations=exc)
