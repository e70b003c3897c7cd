"""The plotting widget: axes with units, a legend, log-x and dB-y, sized to its space."""

from __future__ import annotations

import asyncio

import numpy as np
import pytest
from textual.app import App, ComposeResult

from console.tui.charts import Chart, Series, envelope, log_peaks, to_db


class ChartApp(App):
    def __init__(self, chart: Chart) -> None:
        super().__init__()
        self.chart = chart

    def compose(self) -> ComposeResult:
        yield self.chart


def _shown(chart: Chart) -> str:
    return chart.render().plain


def test_chart_draws_axes_units_and_legend_in_its_space():
    asyncio.run(_axes_units_legend())


async def _axes_units_legend():
    t = np.linspace(0, 0.02, 961)
    chart = Chart(title="Waveform", x_label="time", x_unit="s", y_label="piezo", y_unit="V")
    app = ChartApp(chart)
    async with app.run_test(size=(80, 24)) as pilot:
        chart.set_series(
            [Series("PA", t, 40 * np.sin(2 * np.pi * 250 * t)), Series("PC", t, 10 * t / t[-1])]
        )
        await pilot.pause()
        text = _shown(chart)
        lines = text.splitlines()
        assert "Waveform" in text
        assert "time (s)" in text and "piezo (V)" in text
        assert "PA" in text and "PC" in text  # the legend
        # sized to the space the layout gives: 80 x 24 cells
        assert len(lines) == 24 and max(len(ln) for ln in lines) == 80
        # the axis ticks reach the sine's peak
        assert "40" in text
        await pilot.resize_terminal(120, 40)
        await pilot.pause()
        lines = _shown(chart).splitlines()
        assert len(lines) == 40 and max(len(ln) for ln in lines) == 120


def test_chart_log_x_and_db_y_and_empty():
    asyncio.run(_log_x_db_y())


async def _log_x_db_y():
    f = np.array([0.0, 10.0, 100.0, 1000.0])
    mag = np.array([1.0, 1.0, 0.1, 0.0])
    chart = Chart(
        x_label="frequency", x_unit="Hz", y_label="|X|", y_unit="V", log_x=True, db_y=True
    )
    app = ChartApp(chart)
    async with app.run_test(size=(80, 20)) as pilot:
        assert "nothing to plot" in _shown(chart)
        chart.set_series([Series("spectrum", f, mag)])
        await pilot.pause()
        text = _shown(chart)
        assert "frequency (Hz)" in text and "dB re 1 V" in text
        assert "x: frequency (Hz) (log axis); y: |X| (dB re 1 V)" in chart.summary()
        ((label, x, y),) = chart.drawn()
        assert x.tolist() == [10.0, 100.0, 1000.0]  # 0 Hz has no place on a log axis
        assert y.tolist() == [0.0, -20.0, -120.0]  # a zero sits on the floor, never -inf
        assert "spectrum: x 10..1000, y -120..0" in chart.summary()


def test_envelope_keeps_every_peak_and_to_db_is_20log10():
    x = np.arange(48_000) / 48_000
    y = np.sin(2 * np.pi * 1000 * x)
    y[12_345] = 3.0  # a single-sample spike
    xs, ys = envelope(x, y, 100)
    assert xs.size <= 200 and np.all(np.diff(xs) > 0)
    assert ys.max() == 3.0 and ys.min() == pytest.approx(-1.0, abs=1e-6)
    assert to_db(np.array([10.0, 0.1]), ref=1.0).tolist() == pytest.approx([20.0, -20.0])


def test_log_peaks_is_the_max_of_each_log_spaced_column():
    """Against a second method: columns by digitizing log10(x) on equal steps."""
    rng = np.random.default_rng(3)
    x = np.fft.rfftfreq(48_000, 1 / 48_000)[1:]  # 1 Hz .. 24 kHz, linear bins
    y = rng.normal(size=x.size)
    xs, ys = log_peaks(x, y, 60)
    assert xs.size <= 60 and np.all(np.diff(xs) > 0)
    lx = np.log10(x)
    col = np.minimum(((lx - lx[0]) / (lx[-1] - lx[0]) * 60).astype(int), 59)
    want = [y[col == c].max() for c in range(60) if np.any(col == c)]
    assert ys.tolist() == pytest.approx(want)
    assert xs[:5].tolist() == [1.0, 2.0, 3.0, 4.0, 5.0]  # low bins keep a column each
    assert ys.max() == y.max()  # the peak is never lost
    few_x, few_y = log_peaks(x[:10], y[:10], 60)  # fewer points than columns: as they are
    assert few_x.tolist() == x[:10].tolist() and few_y.tolist() == y[:10].tolist()
