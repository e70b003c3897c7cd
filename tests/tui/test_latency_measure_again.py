"""Latency (F7): ``m`` during its own 10 s measurement says it is measuring already and
how long is left, and does not start the 10 s again (a new operator saw the countdown
jump back without a word)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_latency_measure_demo import _screen


def test_m_again_while_measuring_says_so_and_keeps_the_end(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("latency")
            head = app.query_one("#lat-head")
            await wait_for(pilot, lambda: "m measures" in str(head.render()), 20, "idle hint")
            await pilot.press("m")
            await wait_for(pilot, lambda: "s left" in str(head.render()), 30, "measuring")
            end = pane._measure_until
            await pilot.pause(1.2)
            await pilot.press("m")
            await wait_for(pilot, lambda: "m: measuring already" in _screen(app), 10, "said")
            assert pane._measure_until == end, "m restarted the measurement"

    asyncio.run(scenario())
