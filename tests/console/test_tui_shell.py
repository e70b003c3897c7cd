"""The console shell, driven as a person would: relay toggle, e-stop key, bar state."""

from __future__ import annotations

import asyncio

from textual.widgets import Switch

from console.cli import Context
from console.tui.app import HapTableApp
from console.tui.safety_bar import SafetyBar


async def _wait_for(pilot, cond, timeout_s: float = 5.0) -> None:
    for _ in range(int(timeout_s / 0.05)):
        if cond():
            return
        await pilot.pause(0.05)
    raise AssertionError("condition not reached")


def test_relay_toggle_and_estop(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False)
        async with app.run_test(size=(80, 24)) as pilot:
            await _wait_for(pilot, lambda: app.outputs is not None)
            bar = app.query_one(SafetyBar)
            await _wait_for(pilot, lambda: "E-STOP" in str(bar.render()))
            app.query_one("#relay-1", Switch).value = True
            await _wait_for(pilot, lambda: app.outputs.gate.relay_state() == frozenset({1}))
            await _wait_for(pilot, lambda: "relays closed: 1" in str(bar.render()))
            await pilot.press("ctrl+e")
            await _wait_for(pilot, lambda: app.outputs.gate.estopped)
            assert app.outputs.gate.relay_state() == frozenset()
            await _wait_for(pilot, lambda: str(bar.render()).startswith(" E-STOP:"))
            assert bar.has_class("estop")
            log = app.outputs.relay_log()
            assert [(r.channel, r.closed) for r in log] == [(1, True), (1, False)]
            assert all(r.level_v == (0.0, 0.0) for r in log)
            await pilot.press("ctrl+r")
            await _wait_for(pilot, lambda: not app.outputs.gate.estopped)

    asyncio.run(scenario())
