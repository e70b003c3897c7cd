"""Issue 27, the Scope at 80 x 24: the voltage axis shows its zero whatever the trace's
range, and an e-stop that found the outputs silent says there was no ramp (never
"ramp in 0.00 ms")."""

from __future__ import annotations

import asyncio
import re

import numpy as np
from textual.widgets import Static

from console.cli.main import Context
from console.safety.scope import ScopeTrace
from console.tui.app import HapTableApp
from console.tui.charts import Chart

from .conftest import wait_for
from .test_camera_layout import screen_lines

FS = 48000


def _lopsided_trace() -> ScopeTrace:
    """50 ms: a tone from -3 V to +20 V, then silence; an e-stop in the silence."""
    n = FS // 20
    t = np.arange(n) / FS
    piezo = np.where(t < 0.03, 8.5 + 11.5 * np.sin(2 * np.pi * 250 * t), 0.0)
    volts = np.stack([piezo, np.zeros(n)], axis=1)
    return ScopeTrace(volts, FS, 1000, ("piezo", "screen"), ((1000 + 2000, "estop", "test"),))


def test_the_y_axis_shows_zero_and_a_silent_estop_says_no_ramp(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scope")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 20, "outputs")
            trace = _lopsided_trace()
            app.session.scope = lambda seconds=None: trace  # what the gate passed
            info = app.query_one("#scope-info", Static)
            await wait_for(pilot, lambda: "estop at" in str(info.content), 10, "e-stop shown")
            chart = app.query_one("#scope-chart", Chart)
            rows = screen_lines(app)[chart.region.y : chart.region.bottom]
            labels = [m.group(1) for r in rows if (m := re.match(r"\s*(-?[\d.]+)┤", r))]
            assert labels and any(float(v) == 0.0 for v in labels), labels
            assert any(float(v) >= 20.0 for v in labels), labels
            text = str(info.content)
            assert "0.00 ms" not in text and "already silent: no ramp" in text, text

    asyncio.run(scenario())
