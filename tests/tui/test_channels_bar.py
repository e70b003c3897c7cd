"""On a profile with a channel per patch (sim-4ch) the safety bar shows every output
channel's level by name, and an e-stop silences all of them."""

from __future__ import annotations

import asyncio
import re

from console.cli.main import Context
from console.signals.stimuli import make_stimulus
from console.tui.app import HapTableApp
from console.tui.safety_bar import SafetyBar

from .conftest import wait_for


def _level(text: str, name: str) -> float | None:
    m = re.search(rf"\b{name} +([-+]\d+\.\d) V", text)
    return None if m is None else float(m.group(1))


def test_safety_bar_names_five_channels_and_the_estop_silences_them(plugins):
    async def scenario():
        app = HapTableApp(Context("sim-4ch", plugins), fast=False, initial="relays")
        async with app.run_test(size=(120, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            bar = app.query_one(SafetyBar)

            def text() -> str:
                return str(bar.render())

            await wait_for(pilot, lambda: _level(text(), "screen") is not None, what="levels")
            assert all(_level(text(), n) == 0.0 for n in ("PA", "PB", "PC", "PD", "screen"))
            assert "piezo" not in text()
            plan = make_stimulus("sine-PC", app.session.outputs.limits.sample_rate_hz)
            app.session.outputs.play(plan, wait=False)
            await wait_for(pilot, lambda: abs(_level(text(), "PC") or 0.0) > 0.5, what="PC playing")
            assert _level(text(), "PA") == 0.0 and _level(text(), "PD") == 0.0
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: text().startswith(" E-STOP:"), what="e-stop shown")
            assert app.session.outputs.wait_safe(5)
            assert tuple(app.session.outputs.status()["gate"]["level_v"]) == (0.0,) * 5

    asyncio.run(scenario())
