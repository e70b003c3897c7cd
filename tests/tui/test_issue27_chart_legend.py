"""Issue 27 (Signals): the charts' legend is a row below the plot, never drawn over the
curve, at 120 x 40 and after a resize to 80 x 24 (every ``Chart``: the Signals,
Vibration, Scope and Studies plots)."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.charts import Chart

from .conftest import wait_for

SINE = "sine(200 Hz, 30 V, 0.3 s)*ramp(10 ms)"


def _box(lines: list[str]) -> tuple[list[str], list[str]]:
    """The rows inside the plot's frame (┌ to └) and the rows below it."""
    top = next(i for i, ln in enumerate(lines) if "┌" in ln)
    bottom = next(i for i, ln in enumerate(lines) if "└" in ln)
    return lines[top + 1 : bottom], lines[bottom + 1 :]


def _check(chart: Chart, label: str) -> None:
    lines = chart.render().plain.splitlines()
    assert len(lines) == chart.size.height  # the legend takes a row of the chart's own
    inside, below = _box(lines)
    plot = [ln[ln.index("│") + 1 :] if "│" in ln else ln for ln in inside]
    assert not any(label in ln for ln in plot), "\n".join(lines)  # not on the curve
    assert any(f"⣿ {label}" in ln for ln in below), "\n".join(lines)  # below it
    # the curve's top row is drawn where plotext put its legend (the first columns)
    first = inside[0][inside[0].index("┤") + 1 :][:6]
    assert not any(c.isascii() and c.isalnum() for c in first), inside[0]


def test_the_legend_is_below_the_plot_at_both_sizes(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(120, 40)) as pilot:
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is expr, 30, "expression focused")
            expr.value = SINE
            await pilot.press("enter")
            wave = app.query_one("#sig-wave", Chart)
            spec = app.query_one("#sig-spectrum", Chart)
            await wait_for(pilot, lambda: wave.series and spec.series, 30, "plotted")
            await pilot.pause()
            for size in ((120, 40), (80, 24)):
                if app.size != size:
                    await pilot.resize_terminal(*size)
                    await wait_for(pilot, lambda s=size: tuple(app.size) == s, 10, "resized")
                    await pilot.pause()
                _check(wave, "PA")
                _check(spec, "|X|")

    asyncio.run(scenario())
