"""The calibration wizard's refusal is said in the Camera screen's panel, not also as a
toast, while that screen is in view; from another screen it is a toast (one error, one
place: seventh new-user try)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.session.events import Failed
from console.tui.app import HapTableApp

from .test_screens import _ready


def test_a_calibration_refusal_is_a_toast_only_away_from_the_camera(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(80, 24), notifications=True) as pilot:
            await _ready(app, pilot)
            app.session.emit(
                Failed("calibration", message="touch calibration: here", severity="warning")
            )
            await pilot.pause(0.3)
            said = [str(n.message) for n in app._notifications]
            assert not any("here" in m for m in said), said
            await pilot.press("f1")
            await pilot.pause(0.3)
            app.session.emit(
                Failed("calibration", message="touch calibration: away", severity="warning")
            )
            await pilot.pause(0.3)
            said = [str(n.message) for n in app._notifications]
            assert any("away" in m for m in said), said

    asyncio.run(scenario())
