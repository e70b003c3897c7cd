"""The console's pure helpers: plots, bursts in the twin log, interlock texts, limits."""

from __future__ import annotations

import numpy as np

from console.runtime.twin_log import bursts, dominant_hz
from console.tui.panes.latency import stage_rows
from console.tui.panes.relays import interlock
from console.tui.plots import HalfBlockImage, downsample, frf_plot, sparkline
from plugins.electrostatic.panel import FREQ_RANGE_HZ, clamp_setting, force_text


def _status(estopped=False, busy=False):
    return {"gate": {"estopped": estopped, "relays_closed": []}, "busy": busy}


def test_frf_plot_marks_the_chosen_frequency_and_reports_each_excitation():
    f = np.linspace(0, 600, 601)
    mags = np.vstack([1 / (1 + ((f - f0) / 5) ** 2) for f0 in (100, 200, 300)])
    text = frf_plot(f, mags, ("PA", "PB", "PALL"), width=61, height=8, mark_hz=200.0).plain
    lines = text.splitlines()
    plot = lines[:8]
    # the marker sits in the column of 200 Hz (after the 6-character axis labels)
    col = 6 + 20
    assert all(ln[col] in "│•" for ln in plot)
    # each peak is drawn in the top row at its own column
    assert plot[0][6 + 10] == "•" and plot[0][6 + 30] == "•"
    legend = lines[-1]
    assert "PA" in legend and "PALL" in legend and "200 Hz" in legend
    # the value at the marked frequency is printed for the excitation peaking there
    assert "PB 1" in legend


def test_frf_plot_never_draws_masked_bins():
    f = np.linspace(0, 100, 101)
    mags = np.ones((1, 101))
    mags[0, :10] = 1e3  # huge near DC, but masked
    masked = f < 10
    text = frf_plot(f, mags, ("PA",), width=40, height=6, masked=masked).plain
    assert text.splitlines()[0].strip().startswith("0")  # the axis tops at 0 dB, not 60


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
    assert "waits to close" in waits and "when it ends" in waits
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
