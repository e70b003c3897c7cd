"""AHAP and Meta ``.haptic`` files in and out of the signal library (issue 31).

Files are written here by hand from the public format descriptions, each field used;
the imported signal is rendered and its envelope (the carrier's crests) compared with the
file's breakpoints interpolated by numpy (an independent reference), and the round trip
export -> import keeps the envelope (Hilbert magnitude, both sides) within 1 % of full
scale. No app runs.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.signal import find_peaks, hilbert

from console.cli.haptic_commands import scale_for
from console.core.errors import UserError
from console.safety import Limits
from console.session.audition import audition_plan
from console.signals import ahap, meta_haptic
from console.signals.design import parse_target, render
from console.signals.expr import parse
from console.signals.haptic_files import export_signal, to_expression

FS = 48_000


@pytest.fixture
def scale(profile):
    return scale_for(profile, None)


def _env(x: np.ndarray) -> np.ndarray:
    return np.abs(hilbert(x))


def _crests(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(time, |volts|) at every crest of the carrier: the envelope sampled where the sine
    is +-1 (no transform that rounds the envelope's corners)."""
    k, _ = find_peaks(np.abs(x))
    return k / FS, np.abs(x[k])


def _import(path, reader, scale):
    expr, summary = to_expression(reader.read(path), scale)
    return expr, summary, render(parse(expr), FS, max_s=60)


def _away_from(t: np.ndarray, edges: list[float], w: float) -> np.ndarray:
    ok = np.ones(t.size, bool)
    for e in edges:
        ok &= np.abs(t - e) > w
    return ok


AHAP = {
    "Version": 1.0,
    "Metadata": {"Project": "HapTable tests", "Created": "by hand"},
    "Pattern": [
        {"Event": {"Time": 0.1, "EventType": "HapticContinuous", "EventDuration": 0.5,
                   "EventParameters": [
                       {"ParameterID": "HapticIntensity", "ParameterValue": 0.8},
                       {"ParameterID": "HapticSharpness", "ParameterValue": 0.5},
                       {"ParameterID": "AttackTime", "ParameterValue": 0.05},
                       {"ParameterID": "ReleaseTime", "ParameterValue": 0.1},
                       {"ParameterID": "Sustained", "ParameterValue": 1},
                       {"ParameterID": "AudioVolume", "ParameterValue": 0.3}]}},
        {"Event": {"Time": 0.7, "EventType": "HapticContinuous", "EventDuration": 0.3,
                   "EventParameters": [
                       {"ParameterID": "HapticIntensity", "ParameterValue": 0.6},
                       {"ParameterID": "HapticSharpness", "ParameterValue": 0.2},
                       {"ParameterID": "AttackTime", "ParameterValue": 0.02},
                       {"ParameterID": "DecayTime", "ParameterValue": 0.2},
                       {"ParameterID": "Sustained", "ParameterValue": 0}]}},
        {"Event": {"Time": 1.1, "EventType": "HapticTransient", "EventParameters": [
            {"ParameterID": "HapticIntensity", "ParameterValue": 0.9},
            {"ParameterID": "HapticSharpness", "ParameterValue": 0.7}]}},
        {"Event": {"Time": 0.0, "EventType": "AudioCustom", "EventWaveformPath": "a.wav"}},
        {"Event": {"Time": 0.2, "EventType": "AudioContinuous", "EventDuration": 0.1}},
        {"ParameterCurve": {"ParameterID": "HapticIntensityControl", "Time": 0.2,
                            "ParameterCurveControlPoints": [
                                {"Time": 0.0, "ParameterValue": 1.0},
                                {"Time": 0.2, "ParameterValue": 0.5}]}},
        {"Parameter": {"ParameterID": "HapticIntensityControl", "Time": 0.5,
                       "ParameterValue": 1.0}},
        {"ParameterCurve": {"ParameterID": "HapticSharpnessControl", "Time": 0.1,
                            "ParameterCurveControlPoints": [
                                {"Time": 0.0, "ParameterValue": 0.0},
                                {"Time": 0.4, "ParameterValue": 0.3}]}},
        {"Parameter": {"ParameterID": "AudioVolumeControl", "Time": 0.0, "ParameterValue": 1}},
    ],
}  # fmt: skip


def _ahap_reference(t: np.ndarray) -> np.ndarray:
    """The file's intensity by hand: event shapes x the intensity control."""
    e1 = 0.8 * np.interp(t, [0.1, 0.15, 0.5, 0.6], [0, 1, 1, 0], left=0, right=0)
    e2 = 0.6 * np.interp(t, [0.7, 0.72, 0.92], [0, 1, 0], left=0, right=0)
    control = np.where(t < 0.5, np.interp(t, [0.2, 0.4], [1.0, 0.5]), 1.0)
    return e1 * control + e2


def test_ahap_every_field_imported_within_1_percent(tmp_path, scale):
    f = tmp_path / "every.ahap"
    f.write_text(json.dumps(AHAP), encoding="utf-8")
    expr, summary, x = _import(f, ahap, scale)
    assert "AudioCustom event" in summary and "AudioContinuous event" in summary
    assert "parameter AudioVolume" in summary and "control AudioVolumeControl" in summary
    t, crest = _crests(x)
    ref = _ahap_reference(t) * scale.peak_v
    ok = _away_from(t, [0.1, 0.5, 0.6, 0.7, 1.0], 4e-3) & (t < 1.09)
    err = np.max(np.abs(crest[ok] - ref[ok])) / scale.peak_v
    assert err < 0.01, f"envelope off by {err:.2%}"
    # sharpness 0.5 + control 0.3 * (t - 0.1) / 0.4 -> a log map onto the band
    for t0, s in ((0.3, 0.5 + 0.15), (0.8, 0.2 + 0.3)):
        k = round(t0 * FS)
        ph = np.unwrap(np.angle(hilbert(x)))
        f_hz = (ph[k + 48] - ph[k - 48]) / (2 * np.pi * 96 / FS)
        want = scale.lo_hz * (scale.hi_hz / scale.lo_hz) ** s
        assert f_hz == pytest.approx(want, rel=0.01)


def test_transient_is_a_burst_at_its_time(tmp_path, scale):
    f = tmp_path / "every.ahap"
    f.write_text(json.dumps(AHAP), encoding="utf-8")
    _e, _s, x = _import(f, ahap, scale)
    f_hz = scale.hi_hz  # sharpness 0.7 + the sharpness control's 0.3 held since 0.5 s
    d = scale.burst_s(f_hz)
    k = round(1.1 * FS) + np.argmax(np.abs(x[round(1.1 * FS) :]))
    assert k / FS == pytest.approx(1.1 + d / 2, abs=0.5 / f_hz)
    assert np.abs(x[k]) == pytest.approx(0.9 * scale.peak_v, rel=0.01)
    assert np.max(np.abs(x[round(1.02 * FS) : round(1.099 * FS)])) < 1e-6  # silent before


HAPTIC = {
    "version": {"major": 1, "minor": 0, "patch": 0},
    "metadata": {"editor": "by hand", "source": "", "project": "", "tags": ["test"],
                 "description": "every field"},
    "signals": {"continuous": {"envelopes": {
        "amplitude": [
            {"time": 0.0, "amplitude": 0.0},
            {"time": 0.1, "amplitude": 0.9},
            {"time": 0.3, "amplitude": 0.4},
            {"time": 0.5, "amplitude": 0.4},
            {"time": 0.6, "amplitude": 0.0},
            {"time": 0.8, "amplitude": 0.0, "emphasis": {"amplitude": 0.7, "frequency": 0.3}},
            {"time": 0.9, "amplitude": 0.0}],
        "frequency": [{"time": 0.0, "frequency": 0.2}, {"time": 0.6, "frequency": 0.8}],
        "phase": []}}},
}  # fmt: skip


def test_haptic_every_field_imported_within_1_percent(tmp_path, scale):
    f = tmp_path / "every.haptic"
    f.write_text(json.dumps(HAPTIC), encoding="utf-8")
    expr, summary, x = _import(f, meta_haptic, scale)
    assert "envelope phase" in summary and "1 bursts" in summary
    t, crest = _crests(x)
    amp = HAPTIC["signals"]["continuous"]["envelopes"]["amplitude"]
    ref = np.interp(t, [p["time"] for p in amp], [p["amplitude"] for p in amp]) * scale.peak_v
    ok = (t > 0.01) & (t < 0.75)
    err = np.max(np.abs(crest[ok] - ref[ok])) / scale.peak_v
    assert err < 0.01, f"envelope off by {err:.2%}"
    f_hz = scale.lo_hz * (scale.hi_hz / scale.lo_hz) ** 0.3
    k = round(0.8 * FS) + np.argmax(np.abs(x[round(0.8 * FS) :]))
    assert k / FS == pytest.approx(0.8 + scale.burst_s(f_hz) / 2, abs=0.5 / f_hz)
    assert np.abs(x[k]) == pytest.approx(0.7 * scale.peak_v, rel=0.01)


@pytest.mark.parametrize("fmt", ["ahap", "haptic"])
def test_round_trip_keeps_the_envelope_within_1_percent(fmt, tmp_path, scale):
    design = "sine(180 Hz, 60 V, 0.8 s) * adsr(60 ms, 120 ms, 0.5, 200 ms)"
    x0 = render(parse(design), FS)
    mod = ahap if fmt == "ahap" else meta_haptic
    f = tmp_path / f"rt.{fmt}"
    f.write_text(mod.write(export_signal(x0, scale, "rt"), "round trip"), encoding="utf-8")
    _e, _s, x1 = _import(f, mod, scale)
    assert x1.size == pytest.approx(x0.size, abs=2)
    n = min(x0.size, x1.size)
    err = np.max(np.abs(_env(x0[:n]) - _env(x1[:n]))) / 60.0
    assert err < 0.01, f"round trip envelope off by {err:.2%}"
    ph = np.unwrap(np.angle(hilbert(x1)))
    k = n // 2
    assert (ph[k + 480] - ph[k - 480]) / (2 * np.pi * 960 / FS) == pytest.approx(180, rel=0.01)


def test_peak_never_above_the_gate_and_the_gate_takes_it(tmp_path, scale, profile):
    loud = {"Version": 1, "Pattern": [
        {"Event": {"Time": 0.0, "EventType": "HapticContinuous", "EventDuration": 0.3,
                   "EventParameters": [{"ParameterID": "HapticIntensity", "ParameterValue": 1}]}},
        {"Event": {"Time": 0.1, "EventType": "HapticContinuous", "EventDuration": 0.3,
                   "EventParameters": [{"ParameterID": "HapticIntensity", "ParameterValue": 1},
                                       {"ParameterID": "HapticSharpness", "ParameterValue": 1}]}},
        {"Event": {"Time": 0.15, "EventType": "HapticTransient", "EventParameters": [
            {"ParameterID": "HapticIntensity", "ParameterValue": 1}]}}]}  # fmt: skip
    f = tmp_path / "loud.ahap"
    f.write_text(json.dumps(loud), encoding="utf-8")
    expr, summary, x = _import(f, ahap, scale)
    lo, hi = Limits.from_profile(profile).piezo_range()
    assert np.max(np.abs(x)) <= min(-lo, hi) + 1e-9
    assert "clipped" in summary and "lowered" in summary
    plan = audition_plan(profile, expr, parse_target("PALL"), "loud")
    assert plan.duration_s == pytest.approx(0.4, abs=1e-3)


def test_level_in_volts_and_db(profile):
    assert scale_for(profile, "40 V").peak_v == 40.0
    assert scale_for(profile, "30 dB").peak_v == pytest.approx(31.62, rel=1e-3)
    with pytest.raises(UserError, match="at most 100 V"):
        scale_for(profile, "41 dB")
    with pytest.raises(UserError, match="--level 'loud'"):
        scale_for(profile, "loud")


def test_breakpoint_shapes_against_analytic_references():
    # a glide through two frequencies is the linear chirp: phase 2 pi (f0 t + k t^2 / 2)
    g = render(parse("glide(20 V, 0 s, 100 Hz, 1 s, 300 Hz)"), FS)
    t = np.arange(g.size) / FS
    assert np.max(np.abs(g - 20 * np.sin(2 * np.pi * (100 * t + 100 * t**2)))) < 1e-6
    e = parse("env(0 s, 0 %, 0.25 s, 100 %, 1 s, 50 %)").render(FS, FS)
    tt = np.linspace(0, 1, FS)
    assert np.max(np.abs(e - np.interp(tt, [0, 0.25, 1], [0, 1, 0.5]))) < 1e-12
    assert np.allclose(parse("hann()").render(FS, 101), np.hanning(101))
    for bad, words in (("env(0 s, 0 %, 0 s, 1)", "strictly increasing"),
                       ("env(0 s, 0 %, 1 s)", "odd number"),
                       ("glide(20 V, 0 s, 100 Hz, 1 s, -3 Hz)", "above 0 Hz"),
                       ("glide(20, 0 s, 100 Hz, 1 s, 30 Hz)", "needs a unit")):  # fmt: skip
        with pytest.raises(UserError, match=words):
            parse(bad)


def test_export_refuses_a_signal_above_its_reference(scale):
    x = render(parse("sine(200 Hz, 150 V, 0.2 s) * ramp(10 ms)"), FS)
    with pytest.raises(UserError, match="--level 150 V"):
        export_signal(x, scale, "loud")


def test_cli_import_then_play_dry_run(tmp_path, capsys):
    from console.cli.main import main

    f = tmp_path / "every.haptic"
    f.write_text(json.dumps(HAPTIC), encoding="utf-8")
    assert main(["signals", "import", str(f), "--level", "40 V"]) == 0
    out = capsys.readouterr().out
    assert "every.haptic (.haptic)" in out and "saved every" in out
    assert main(["signals", "play", "every", "--patch", "PA", "--dry-run"]) == 0
    out_f = tmp_path / "back.ahap"
    assert main(["signals", "export", "every", "--format", "ahap", "-o", str(out_f)]) == 0
    doc = json.loads(out_f.read_text())
    assert doc["Pattern"][0]["Event"]["EventType"] == "HapticContinuous"
    curves = [p["ParameterCurve"] for p in doc["Pattern"][1:]]
    assert all(len(c["ParameterCurveControlPoints"]) <= 16 for c in curves)
