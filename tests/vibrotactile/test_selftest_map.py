"""The self-test against the stored map, the cracked patch and the amplifiers' monitors.

Numerics first (no twin): the sensor's common factor fitted out of a mix (against the
analytic structural modification of a point mass), the crack's digital filter against its
analytic model, a detached and a cracked path told apart by their band levels, the
monitor's gains read into findings. Then one twin (fast-forward): a table without a
baseline tested against a map of the twin's own FRFs (a laser's: no sensor mass) finds a
cracked patch on its first test and names it, a healthy one passes and keeps its baseline;
the monitor finds a weak amplifier channel without the accelerometer."""

from __future__ import annotations

import dataclasses
import math
from types import SimpleNamespace

import numpy as np
import pytest

from console.plugin_api import EXCITATIONS, PATCHES, UserError, make_map
from plugins.twin.crack import CRACK_HZ, crack_filter, crack_response
from plugins.vibrotactile.roving import h1
from plugins.vibrotactile.selftest import Layout, Thresholds, findings, mix
from plugins.vibrotactile.selftest_map import map_baseline, mix_with_sensor
from plugins.vibrotactile.selftest_monitor import monitor_findings
from plugins.vibrotactile.selftest_shape import spread_db

F = np.arange(40.0, 626.0)
FR = np.array([52.0, 97.0, 151.0, 233.0, 318.0, 402.0, 517.0, 590.0])  # the plate's modes
LAY = Layout(
    {p: i + 1 for i, p in enumerate(PATCHES)}, dict.fromkeys(PATCHES, "piezo"), {"piezo": 1}
)


def _paths(seed: int = 0) -> np.ndarray:
    """Five modal FRFs (m/s^2 per volt) PA..PD, PALL at one point: shared poles, own residues."""
    rng = np.random.default_rng(seed)
    w, wr = 2 * np.pi * F[:, None], 2 * np.pi * FR[None, :]
    modes = -(w**2) / (wr**2 - w**2 + 2j * 0.01 * wr * w)  # (F, R)
    res = rng.standard_normal((4, FR.size))
    b = res @ modes.T
    return np.vstack([b, b.sum(0)])


def _mass_factor() -> np.ndarray:
    """1 / (1 - m w^2 H_jj): a 7 g sensor at j, H_jj modal (the structural modification)."""
    w = 2 * np.pi * F
    eps = np.array([0.004, 0.01, 0.002, 0.006, 0.0, 0.008, 0.003, 0.005])  # m phi_r(j)^2
    wr = 2 * np.pi * FR  # 7 g on 2.6 kg of glass: eps ~ 0.01 at most
    hjj = np.sum(eps[None] / (wr[None] ** 2 - w[:, None] ** 2 + 2j * 0.01 * wr * w[:, None]), 1)
    return 1 / (1 - w**2 * hjj)


def _got(h: np.ndarray) -> dict:
    return {"paths": tuple(EXCITATIONS), "freqs_hz": F, "h": h}


def test_the_sensors_mass_is_fitted_out_and_a_swap_still_shows():
    b = _paths()
    base = {"paths": np.array(EXCITATIONS), "freqs_hz": F, "h": b}
    g = _mass_factor()
    plain = mix(_got(b * g), base)  # without the factor: the loaded FRFs look changed
    assert plain["residual"].max() > 0.1
    m = mix_with_sensor(_got(b * g), base)
    assert np.allclose(np.abs(m["c"]), np.eye(4), atol=0.02)
    assert m["residual"].max() < 0.01 and abs(m["pall_db"]) < 0.1
    k = np.median(g.real) + 1j * np.median(g.imag)  # g is fitted up to its scale
    assert np.allclose(m["g"] * k, g, atol=0.02)
    assert findings(m, LAY) == []
    sw = b.copy()
    sw[[0, 2]] = sw[[2, 0]]  # PA and PC swapped
    got = {(f.kind, f.subject) for f in findings(mix_with_sensor(_got(sw * g), base), LAY)}
    assert got == {("swapped", "PA/PC")}


def test_the_crack_filter_follows_its_analytic_model():
    fs = 48000
    t = np.arange(fs) / fs
    x = np.sin(2 * np.pi * (20 * t + 0.5 * 680 * t**2))  # a linear chirp 20-700 Hz
    x = np.concatenate([x, np.zeros(fs // 4)])
    f, h, _ = h1(x, crack_filter(x, fs), fs)
    keep = (f >= 40) & (f <= 625)
    err_db = 20 * np.log10(np.abs(h[keep]) / np.abs(crack_response(f[keep])))
    assert np.max(np.abs(err_db)) < 0.1
    # the level drops over part of the band: -4.4 dB low, a peak near CRACK_HZ, -10 dB at 625
    assert abs(20 * np.log10(abs(crack_response(np.array([40.0]))[0])) + 4.4) < 0.3
    assert abs(crack_response(np.array([CRACK_HZ]))[0]) > 1.0
    assert 20 * np.log10(abs(crack_response(np.array([625.0]))[0])) < -8


def test_a_detached_and_a_cracked_patch_are_told_apart():
    b = _paths(1)
    base = {"paths": np.array(EXCITATIONS), "freqs_hz": F, "h": b}
    rng = np.random.default_rng(3)
    noise = 1e-3 * np.abs(b).mean() * rng.standard_normal(b.shape)
    det, cr = b + noise, b + noise
    det[1] = 0.03 * b[1] + noise[1]  # PB detached: 3 % of its coupling left
    cr[3] = crack_response(F) * b[3] + noise[3]  # PD cracked
    d = findings(mix(_got(det), base), LAY)
    c = findings(mix(_got(cr), base), LAY)
    assert [(f.kind, f.subject) for f in d] == [("detached", "PB")]
    assert [(f.kind, f.subject) for f in c] == [("cracked", "PD")]
    assert "cracked: replace it" in c[0].line and "re-glue" in d[0].line
    assert spread_db(F, det[:4], b[:4] * [[1], [0.03], [1], [1]]).max() < 1.0
    assert Thresholds().crack_db < 12


def test_the_monitor_names_a_dead_and_a_weak_channel():
    assert monitor_findings({"piezo": 1.01}, LAY, {"piezo": 50.0}) == []
    (dead,) = monitor_findings({"piezo": 1e-4}, LAY, {"piezo": 50.0})
    assert dead.kind == "dead_channel" and "check the amplifier" in dead.line
    (weak,) = monitor_findings({"piezo": 0.4}, LAY, {"piezo": 50.0})
    assert weak.kind == "weak_channel" and "-8.0 dB" in weak.line
    assert "gain 20 instead of 50" in weak.line


def test_a_map_without_the_reference_point_or_a_patch_is_one_line():
    pts = np.array([[100.0, 100.0]])
    frf = np.ones((5, 1, F.size), complex)
    vmap = make_map(frf, F, np.array([1]), pts, EXCITATIONS)
    with pytest.raises(UserError) as e:
        map_baseline(vmap, (52, 281.73, 283.645), (40.0, 625.0))
    assert "no point at the reference point 52" in str(e.value) and "\n" not in str(e.value)
    part = make_map(frf[:4], F, np.array([1]), pts, EXCITATIONS[:4], require_all=False)
    with pytest.raises(UserError, match="no PALL in it"):
        map_baseline(part, (1, 100.0, 100.0), (40.0, 625.0))


@pytest.fixture(scope="module")
def twin(tmp_path_factory):
    from console.config.plugins import load_plugins
    from console.config.profile import load_profile
    from console.plugin_api.runtime import open_outputs
    from plugins.twin.plate.vibrometer import TwinVibrometer
    from plugins.vibrotactile.selftest import reference_point

    pm = load_plugins()
    prof = load_profile("sim", pm)
    d = tmp_path_factory.mktemp("selftest-map")
    data = {
        **prof.data,
        "audio": {**prof.data["audio"], "block_size": 1024},
        "selftest": {"baseline": str(d / "baseline.npz")},
    }
    prof = dataclasses.replace(prof, data=data)
    ref = reference_point(prof)
    # a laser's map of the twin at the reference point and a neighbour (no sensor mass)
    pts = np.array([[ref[1], ref[2]], [ref[1] + 60, ref[2]]])
    freqs = np.arange(0.0, 700.0, 0.5)
    frf = TwinVibrometer(prof).true_frf_um_per_v(pts[:, 0], pts[:, 1], freqs)
    vmap = make_map(frf, freqs, np.array([ref[0], ref[0] + 1]), pts, EXCITATIONS)
    with open_outputs(prof, pm, fast=True) as out:
        yield SimpleNamespace(out=out, profile=prof, pm=pm, vmap=vmap, baseline=d / "baseline.npz")


def test_a_first_self_test_against_the_map_names_a_cracked_patch(twin):
    from console.plugin_api.runtime import inject_twin_faults
    from plugins.vibrotactile.selftest import run_selftest

    inject_twin_faults(twin.out, {"cracked": ["PC"]})
    r = run_selftest(twin.out, twin.profile, quick=True, vmap=twin.vmap)
    assert not r["ok"] and not r["saved"] and not twin.baseline.exists()
    assert [(f["kind"], f["subject"]) for f in r["findings"]] == [("cracked", "PC")]
    assert r["against"].startswith("vibration map")
    inject_twin_faults(twin.out, {"coupling": [1.01, 0.99, 1.0, 1.02]})  # healthy, drifted
    r = run_selftest(twin.out, twin.profile, quick=True, vmap=twin.vmap)
    assert r["ok"] and r["saved"] and twin.baseline.exists(), r["lines"]
    assert r["lines"][0] == "all paths healthy against the vibration map"


def test_the_amplifier_monitor_finds_a_weak_channel_without_the_accelerometer(twin):
    from console.plugin_api.runtime import inject_twin_faults
    from plugins.vibrotactile.selftest_monitor import run_monitor_selftest

    inject_twin_faults(twin.out, {"weak_channels": ["piezo"]})
    r = run_monitor_selftest(twin.out, twin.profile)
    assert not r["ok"] and math.isclose(r["gain"]["piezo"], 0.4, rel_tol=0.02)
    assert r["findings"][0]["kind"] == "weak_channel"
    inject_twin_faults(twin.out, {})
    assert run_monitor_selftest(twin.out, twin.profile)["ok"]


def test_a_missing_map_file_is_one_line_before_anything_plays(twin, tmp_path):
    from plugins.vibrotactile.cli.selftest import selftest_report

    ctx = SimpleNamespace(profile=twin.profile, pm=twin.pm)
    with pytest.raises(UserError) as e:
        selftest_report(ctx, quick=True, map_file=str(tmp_path / "nope.npz"))
    msg = str(e.value)
    assert msg.startswith(str(tmp_path / "nope.npz")) and "no such vibration map" in msg
    assert "--map" in msg and "\n" not in msg


def test_the_self_tests_numpy_chirp_is_scipys_logarithmic_chirp():
    from scipy.signal import chirp

    from plugins.vibrotactile.selftest import FULL
    from plugins.vibrotactile.selftest_chirp import record_v

    s, fs = FULL.roving(), 48000
    x = record_v(s, fs)
    n = int(round(s.sweep_s * fs))
    t = np.arange(n) / fs
    ref = s.level_v * chirp(t, s.f_start_hz, s.sweep_s, s.f_stop_hz, "logarithmic", phi=-90)
    m = int(round(s.fade_s * fs))
    assert np.max(np.abs(x[m : n - m] - ref[m : n - m])) < 1e-9 * s.level_v
    assert x.size == n + int(round(s.tail_s * fs)) and not x[n:].any()
    assert abs(x[0]) < 1e-12 and abs(x[n - 1]) < 0.01 * s.level_v  # faded: no click
