"""The console's pure helpers: plots, bursts in the twin log, interlock texts, limits."""

from __future__ import annotations

import numpy as np

from console.runtime.twin_log import bursts, dominant_hz
from console.tui.panes.latency import stage_rows
from console.tui.panes.relays import interlock
from console.tui.plots import HalfBlockImage, downsample, frf_series, sparkline
from plugins.electrostatic.panel import FREQ_RANGE_HZ, clamp_setting, force_text


def _status(estopped=False, busy=False):
    return {"gate": {"estopped": estopped, "relays_closed": []}, "busy": busy}


def test_frf_series_mark_the_chosen_frequency_with_each_excitations_value():
    f = np.linspace(0, 600, 601)
    mags = np.vstack([1 / (1 + ((f - f0) / 5) ** 2) for f0 in (100, 200, 300)])
    series = frf_series(f, mags, ("PA", "PB", "PALL"), mark_hz=200.0)
    labels = [s.label for s in series]  # each value with its unit
    assert labels == ["PA 0.00249 µm/V", "PB 1 µm/V", "PALL 0.00249 µm/V", "plays at 200 Hz"]
    np.testing.assert_array_equal(series[1].y, mags[1])  # µm/V as measured: the chart does dB
    mark = series[-1]
    assert list(mark.x) == [200.0, 200.0] and mark.y[1] == 1.0 and mark.y[0] == 1e-3


def test_frf_series_never_draw_masked_bins_or_bins_above_the_band():
    from console.tui.charts import Chart

    f = np.linspace(0, 100, 101)
    mags = np.ones((1, 101))
    mags[0, :10] = 1e3  # huge near DC, but masked
    masked = f < 10
    (pa,) = frf_series(f, mags, ("PA",), masked=masked, band_hz=90.0)
    assert np.isnan(pa.y[:10]).all() and np.isnan(pa.y[91:]).all()
    chart = Chart(x_unit="Hz", y_label="|H|", y_unit="µm/V", db_y=True)
    chart.series = (pa,)
    ((label, x, y),) = chart.drawn(columns=200)
    assert label == "PA" and x.min() == 10 and x.max() == 90 and np.all(y == 0.0)  # 0 dB
    assert "|H| (dB re 1 µm/V)" in chart.summary()
    assert frf_series(f, mags, ("PA",), masked=np.ones(101, bool)) == []


def test_sparkline_uses_the_width_it_is_given():
    values = np.arange(100.0)
    assert len(sparkline(values, 73)) == 73 and sparkline(values, 73)[-1] == "█"
    assert len(sparkline(values[:5], 73)) == 5  # fewer values: fewer bars


def test_sparkline_scales_to_its_max():
    assert sparkline([0, 1, 2, 4]) == "▁▃▅█"  # index round(v / max * 7)
    assert sparkline([]) == ""
    assert sparkline([0, 0]) == "▁▁"


def test_downsample_is_an_area_mean():
    img = np.arange(16, dtype=float).reshape(4, 4)
    small = downsample(img, cols=2, rows=1)
    assert small.shape == (2, 2)
    assert small[0, 0] == np.mean([0, 1, 4, 5])


def test_half_block_image_renders_two_pixels_per_cell():
    from rich.console import Console

    grey = np.zeros((4, 3))
    grey[0] = 255
    ov = np.zeros((4, 3, 3), np.uint8)
    ov[3, 1] = (255, 0, 0)
    con = Console(width=10, color_system="truecolor", record=True)
    con.print(HalfBlockImage(grey, ov))
    segs = [ln for ln in con.export_text().splitlines() if ln]
    assert segs == ["▀▀▀", "▀▀▀"]


def test_bursts_find_each_stimulus_with_its_frequency():
    fs = 48000
    t = np.arange(4800) / fs
    tone = np.sin(2 * np.pi * 465.0 * t) * np.hanning(t.size)
    rec = np.zeros((20000, 2))
    rec[1000:5800, 0] = 80 * tone
    rec[10000:14800, 1] = 50 * np.sin(2 * np.pi * 180.0 * t) * np.hanning(t.size)
    b = bursts(rec, fs)
    assert len(b) == 2
    assert abs(b[0]["piezo_freq_hz"] - 465.0) < 1.0 and b[0]["screen_freq_hz"] is None
    assert abs(b[1]["screen_freq_hz"] - 180.0) < 1.0
    assert b[0]["start"] == 1001  # the window starts at exactly zero
    assert abs(b[0]["piezo_peak_v"] - 80.0) < 0.1


def test_dominant_frequency_between_bins():
    fs = 1000
    x = np.sin(2 * np.pi * 123.4 * np.arange(500) / fs)
    assert abs(dominant_hz(x, fs) - 123.4) < 0.2
    assert dominant_hz(np.zeros(100), fs) is None


def test_interlock_says_why_a_toggle_waits_or_is_refused():
    assert "e-stop" in interlock(1, _status(estopped=True), {}, {})
    assert "refused" in interlock(1, _status(estopped=True), {1: True}, {})
    waits = interlock(2, _status(busy=True), {2: True}, {})
    assert "waits to close until the stimulus ends" in waits
    assert "guard gap" in interlock(2, _status(), {2: False}, {})
    assert "refused: board failed" in interlock(3, _status(), {}, {3: "board failed"})
    assert "ready" in interlock(4, _status(), {}, {})


def test_electrostatic_setting_stays_inside_the_limits():
    assert clamp_setting(250.0, 180.0, 200.0) == (200.0, 180.0)
    assert clamp_setting(-10.0, 1.0, 200.0) == (0.0, FREQ_RANGE_HZ[0])
    assert clamp_setting(50.0, 1e6, 200.0)[1] == FREQ_RANGE_HZ[1]


def test_force_text_names_threshold_and_force():
    meta = {
        "force_mean_n": 0.012,
        "force_peak_n": 0.024,
        "friction_change_mean_n": 0.006,
        "friction_base_n": 0.25,
        "threshold_vpp": 40.0,
        "margin_db": 8.0,
        "below": False,
    }
    text = force_text(meta)
    assert "12.0 mN mean" in text and "+8.0 dB above threshold" in text
    assert "below the detection threshold" in force_text({**meta, "below": True})


def test_latency_rows_follow_the_pipeline_order():
    snap = {
        "stages": {"vision": {"p50_ms": 4.0}, "classify": {"p50_ms": 1.0}, "extra": {}},
        "capture_to_arrival": {"p50_ms": 0.5},
        "end_to_end": {"p50_ms": 6.0},
    }
    assert [r[0] for r in stage_rows(snap)] == [
        "capture",
        "vision",
        "classify",
        "end to end",
        "extra",
    ]
