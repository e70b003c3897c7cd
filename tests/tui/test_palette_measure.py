"""The palette's "Measure vibration map" from another screen shows the Vibration screen
with its question or its measurement in view (its question lapsed on the hidden screen)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_measure_from_the_palette_shows_the_vibration_screen_and_what_it_asks(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("ctrl+p")
            await wait_for(pilot, lambda: type(app.screen).__name__ == "SafetyPalette")
            await pilot.press(*"Measure vibration")
            await pilot.pause(0.5)
            await pilot.press("enter")
            await wait_for(pilot, lambda: app.query_one("#tabs").active == "vibration", 10)
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: "measur" in str(pane.status_text), 10, "status")
            await pilot.pause(0.5)
            assert app.query_one("#tabs").active == "vibration"
            assert "measur" in str(pane.status_text)

    asyncio.run(scenario())
