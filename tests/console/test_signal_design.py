"""Signals as data: renderers against analytic references, the expression syntax, hard cases."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import hilbert

from console.core.errors import UserError
from console.signals.design import (
    Target,
    dominant_hz,
    parse_target,
    render,
    signal_plan,
    spectrum,
    summarize,
)
from console.signals.expr import parse
from console.signals.waveforms import linear_chirp, ramp_envelope, tone

FS = 48_000


def volts(expr: str, max_s: float = 60.0) -> np.ndarray:
    return render(parse(expr), FS, max_s=max_s)


@pytest.mark.parametrize("kind", ["sine", "square", "saw", "triangle"])
def test_waveform_fundamental_and_peak(kind):
    y = volts(f"{kind}(250 Hz, 40 V, 1 s)")
    assert y.size == FS
    assert np.max(np.abs(y)) == pytest.approx(40.0, rel=1e-3)
    f, mag = spectrum(y, FS)
    assert f[np.argmax(mag)] == pytest.approx(250.0)
    assert dominant_hz(y, FS) == pytest.approx(250.0, abs=0.1)


def test_waveform_shapes_match_their_fourier_series():
    # square: odd harmonics at 4/(pi k); saw: all harmonics at 2/(pi k); triangle 8/(pi k)^2
    for kind, k, amp in (
        ("square", 3, 4 / (3 * np.pi)),
        ("saw", 2, 2 / (2 * np.pi)),
        ("triangle", 3, 8 / (3 * np.pi) ** 2),
    ):
        f, mag = spectrum(volts(f"{kind}(100 Hz, 1 V, 1 s)"), FS)
        assert mag[np.argmin(abs(f - 100 * k))] == pytest.approx(amp, rel=0.03), kind
    f, mag = spectrum(volts("square(100 Hz, 1 V, 1 s)"), FS)
    assert mag[np.argmin(abs(f - 200))] < 1e-3  # no even harmonics


def test_sine_equals_the_existing_tone_and_starts_at_zero():
    y = volts("sine(250 Hz, 20 V, 1 s) * ramp(20 ms)")
    np.testing.assert_allclose(y, tone(250.0, 20.0, 1.0, FS), atol=1e-9)
    assert volts("triangle(10 Hz, 1 V, 1 s)")[0] == pytest.approx(0.0, abs=1e-9)


def test_chirp_instantaneous_frequency_linear_and_log():
    y = volts("chirp(100 Hz, 500 Hz, 10 V, 2 s)")
    # a second method: the existing closed-form sweep
    np.testing.assert_allclose(
        y * ramp_envelope(y.size, round(0.02 * FS)),
        linear_chirp(100.0, 500.0, 10.0, 2.0, FS),
        atol=1e-6,
    )
    t = np.arange(y.size) / FS
    for expr, expected in (
        ("chirp(100 Hz, 500 Hz, 10 V, 2 s)", 100 + 200 * t),
        ("logchirp(100 Hz, 1 kHz, 10 V, 2 s)", 100 * 10 ** (t / 2)),
    ):
        phase = np.unwrap(np.angle(hilbert(volts(expr))))
        inst = np.diff(phase) * FS / (2 * np.pi)
        mid = slice(FS // 10, -FS // 10)  # away from the analytic signal's edge effects
        np.testing.assert_allclose(inst[mid], expected[:-1][mid], rtol=0.01)


def test_adsr_segment_levels_and_lengths():
    env = render(parse("linramp(1, 1) * sine(12 kHz, 1 V, 1 s)"), FS)  # sanity of stretch
    assert env.size == FS
    x = render(parse("adsr(100 ms, 100 ms, 50 %, 200 ms) * square(1 Hz, 1 V, 1 s)"), FS)
    # the 1 Hz square is +1 for the first half second, -1 after: the envelope shows through
    assert x[0] == 0.0 and x[-1] == 0.0
    assert x[round(0.1 * FS)] == pytest.approx(1.0, abs=1e-3)  # attack top
    assert x[round(0.2 * FS)] == pytest.approx(0.5)  # decayed to the sustain
    assert x[round(0.45 * FS)] == pytest.approx(0.5)  # sustain
    assert x[round(0.7 * FS)] == pytest.approx(-0.5)  # sustain, square's second half
    assert x[round(0.9 * FS)] == pytest.approx(-0.25, abs=1e-3)  # half-way through release
    assert x[round(0.05 * FS)] == pytest.approx(0.5, abs=1e-3)  # half-way through attack


def test_exponential_and_linear_ramps():
    x = render(parse("expramp(1 %, 100 %) * square(1 Hz, 1 V, 0.4 s)"), FS)
    assert x[0] == pytest.approx(0.01) and x[-1] == pytest.approx(1.0)
    assert x[x.size // 2] == pytest.approx(0.1, rel=1e-3)  # geometric middle
    x = render(parse("linramp(0, 1, 1 s) * square(0.5 Hz, 2 V, 1 s)"), FS)
    assert x[FS // 2] == pytest.approx(1.0, abs=1e-4)


def test_sequences_repeats_sums_and_gains():
    one = volts("seq(sine(250 Hz, 4 V, 0.5 s) * ramp(5 ms), silence(0.2 s))")
    assert one.size == round(0.7 * FS)
    three = volts("seq(sine(250 Hz, 4 V, 0.5 s) * ramp(5 ms), silence(0.2 s)) * 3")
    assert three.size == 3 * one.size
    np.testing.assert_array_equal(three, np.tile(one, 3))
    np.testing.assert_array_equal(volts("repeat(silence(10 ms), 4)"), np.zeros(1920))
    s = volts("sine(100 Hz, 1 V, 1 s) + sine(300 Hz, 2 V, 0.5 s)")
    assert s.size == FS and np.max(np.abs(s[FS // 2 + 10 :])) <= 1.0  # the short part ended
    half = volts("sine(100 Hz, 10 V, 1 s) * -6.0206 dB")
    assert np.max(np.abs(half)) == pytest.approx(5.0, rel=1e-4)
    np.testing.assert_allclose(volts("sine(100 Hz, 10 V, 1 s) * 50 %"), half, rtol=1e-4)
    np.testing.assert_allclose(volts("-sine(100 Hz, 10 V, 1 s)"), -2 * half, rtol=1e-4)
    am = volts("sine(250 Hz, 40 V, 1 s) * sine(5 Hz, 100 %, 1 s)")
    assert np.max(np.abs(am)) <= 40.0


def test_noise_is_reproducible_from_its_seed_and_bounded():
    a, b = volts("noise(5 V, 1 s, seed=7)"), volts("noise(5 V, 1 s, seed=7)")
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, volts("noise(5 V, 1 s, seed=8)"))
    assert np.max(np.abs(a)) <= 5.0
    assert np.sqrt(np.mean(a**2)) == pytest.approx(5 / np.sqrt(3), rel=0.02)  # uniform RMS


def test_summary_numbers():
    s = summarize(volts("sine(250 Hz, 40 V, 1 s)"), FS)
    assert s.duration_s == 1.0
    assert s.peak_v == pytest.approx(40.0, rel=1e-4)
    assert s.rms_v == pytest.approx(40 / np.sqrt(2), rel=1e-4)
    assert s.dominant_hz == pytest.approx(250.0, abs=0.1)
    assert summarize(np.zeros(100), FS).dominant_hz == 0.0


@pytest.mark.parametrize(
    ("expr", "says"),
    [
        ("sine(250 Hz, 40 V, 0 s)", "duration 0 s"),
        ("silence(0 s)", "shorter than two samples"),
        ("sine(250 Hz, 40 V, 1 s) * 3000", "longer than [limits] max_plan_s"),
        ("repeat(sine(250 Hz, 4 V, 1000 s), 100000)", "longer than [limits] max_plan_s"),
        ("sine(250 Hz, 4 V, 1e400 s)", "not a finite number"),
        ("sine(250, 40 V, 1 s)", "frequency 250 needs a unit; write 250 Hz"),
        ("sine(250 Hz, 1 s, 40 V)", "amplitude 1 s is a duration, expected a voltage"),
        ("sine(250 Hz, 40 V, 1 s) * 0.5", "for a gain write"),
        ("sin(250 Hz, 4 V, 1 s)", "did you mean 'sine'"),
        # a quote is no character of the language: named before any name is looked up
        ("__import__('os').system('true')", '"\'" at column 12 is not part of the signal'),
        ("__import__('os')", '"\'" at column 12 is not part of the signal syntax'),
        ("__import__(os)", "unknown function '__import__'"),
        ("sine(250 Hz, 4 V, 1 s).real", "not part of the signal syntax"),
        ("open", "'open' is not part of the signal syntax"),
        ("sine(250 Hz, 4 V, 1 s", "does not read"),
        ("sine(30 kHz, 4 V, 1 s)", "below 24000 Hz"),
        ("ramp(10 ms)", "alone has no length"),
        ("sine(5 Hz, 100 %, 1 s)", "not volts"),
        ("sine(1 Hz, 1 V, 1 s) * sine(1 Hz, 1 V, 1 s)", "volts squared"),
        ("adsr(1 s, 1 s, 0.5, 1 s) * sine(2 Hz, 1 V, 1 s)", "longer than the 1 s it shapes"),
        ("repeat(sine(250 Hz, 4 V, 1 s), 0)", "repeat count 0"),
        ("sine(1 Hz, 1 V, 1 s) / 2", "only +, - and *"),
        ("-" * 200 + "silence(1 s)", "nested too deeply"),
        ("", "empty signal"),
    ],
)
def test_bad_expressions_get_one_line_naming_the_part(expr, says):
    with pytest.raises(UserError) as err:
        volts(expr)
    msg = str(err.value)
    assert says in msg and "\n" not in msg


def test_huge_durations_are_refused_before_allocation(monkeypatch):
    import console.signals.design as sd

    def no_alloc(*a, **k):
        raise AssertionError("allocated")

    monkeypatch.setattr(sd.Seq, "render", no_alloc)
    with pytest.raises(UserError, match="max_plan_s"):
        render(parse("repeat(sine(250 Hz, 4 V, 10 s), 100000)"), FS, max_s=3600)


def test_targets_and_plans():
    assert parse_target("PA") == Target(frozenset({"PA"}))
    assert parse_target("PA+PC") == parse_target("pa, pc") == Target(frozenset({"PA", "PC"}))
    assert parse_target("PALL").patches == frozenset({"PA", "PB", "PC", "PD"})
    assert parse_target("screen").screen
    for bad, says in (
        ("PE", "unknown patch 'PE'"),
        ("PA,screen", "plays alone"),
        ("", "no target"),
    ):
        with pytest.raises(UserError, match=says):
            parse_target(bad)
    y = volts("sine(250 Hz, 4 V, 0.1 s) * ramp(5 ms)")
    seg = signal_plan(y, parse_target("screen"), FS, "x").segments[0]
    assert seg.screen and not seg.patches and not seg.piezo_v.any()
    seg = signal_plan(y, parse_target("PA,PC"), FS, "x").segments[0]
    assert seg.patches == {"PA", "PC"} and not seg.screen and not seg.screen_v.any()


def test_nan_and_inf_never_reach_a_plan():
    from console.signals.design import Level, Mix, Wave

    for bad in ("nan", "inf", "sine(250 Hz, nan V, 1 s)", "sine(250 Hz, 1e999 V, 1 s)"):
        with pytest.raises(UserError) as err:
            volts(bad)
        assert "\n" not in str(err.value)
    # a tree built in code (not parsed) is still checked after rendering
    node = Mix("*", (Wave("sine", 10.0, float("nan"), 1.0), Level(1.0, 1.0)))
    with pytest.raises(UserError, match="not a number at 0 s"):
        render(node, FS)


def test_lowpass_matches_the_butterworth_magnitude_and_has_no_delay():
    # filtfilt of an order-4 Butterworth: |H(f)|^2 = 1 / (1 + (f / fc)^8), zero phase
    for f in (250.0, 500.0, 1000.0, 2000.0):
        y = volts(f"lowpass(sine({f} Hz, 10 V, 1 s), 1 kHz)")
        mid = slice(FS // 4, 3 * FS // 4)  # away from the ends
        ref = 10 * np.sin(2 * np.pi * f * np.arange(FS) / FS) / (1 + (f / 1000.0) ** 8)
        np.testing.assert_allclose(y[mid], ref[mid], atol=0.02)
    with pytest.raises(UserError, match="not an envelope"):
        parse("lowpass(ramp(5 ms), 1 kHz)")
    with pytest.raises(UserError, match="below 24000 Hz"):
        volts("lowpass(silence(1 s), 30 kHz)")
    assert volts("lowpass(sine(100 Hz, 1 V, 1 ms), 1 kHz)").size == 48
