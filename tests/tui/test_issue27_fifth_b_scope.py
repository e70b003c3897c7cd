"""Issue 27 (fifth, b): the Scope screen at 80 x 24: ``+`` on the last plan's view zooms
into the plan (a narrower window around its middle, still the plan), ``-`` back out."""

from __future__ import annotations

import asyncio

from textual.widgets import Static

from console.cli.main import Context
from console.signals.stimuli import make_stimulus
from console.tui.app import HapTableApp

from .conftest import wait_for

FS = 48000


def _head(app) -> str:
    return " ".join(str(app.query_one("#scope-head", Static).content).split())


def test_plus_zooms_into_the_plan_shown_and_minus_back_out(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scope")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            pane = app.pane("scope")
            assert app.session.play_plan(make_stimulus("sine-PB", FS), wait=True)
            await wait_for(pilot, lambda: app.session.last_plan_trace() is not None, 30)
            await pilot.press("p")
            await wait_for(pilot, lambda: "FROZEN ON THE LAST PLAN" in _head(app), 30, "p")
            whole = pane.shown.n
            assert "the whole plan" in _head(app)
            await pilot.press("plus")
            head = _head(app)
            assert head.startswith("FROZEN ON THE LAST PLAN | 1000 ms shown"), head
            assert "window 1000 ms around its middle" in head
            assert pane.shown.peak_v()["piezo"] == 20.0  # the plan's content, not 0 V
            await pilot.press("plus")
            assert "FROZEN ON THE LAST PLAN | 500 ms shown" in _head(app)
            assert pane.shown.peak_v()["piezo"] == 20.0
            await pilot.press("minus")
            assert "FROZEN ON THE LAST PLAN | 1000 ms shown" in _head(app)
            await pilot.press("minus")
            assert "the whole plan" in _head(app) and pane.shown.n == whole

    asyncio.run(scenario())
