"""A new operator's try, finding 16b (80 x 24): after the first ``m`` a four-row hint
about accelerometers stayed for the rest of the session and pushed the grid down. It is
one line now, naming where it is said whole (``?``), and the help has it whole."""

from __future__ import annotations

import asyncio

from textual.widgets import Static

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def test_the_accelerometer_hint_is_one_line_and_the_help_says_it_whole(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: pane.focus_target is app.focused, 30, "grid")
            await pilot.press("m")
            found = lambda: pane.query("#vib-roving")  # noqa: E731
            await wait_for(pilot, lambda: bool(found()), 30, "the hint")
            hint = found().first(Static)
            await pilot.pause(0.2)
            assert "accelerometer" in str(hint.render())
            assert hint.size.height == 1, str(hint.render())
            assert "[audio_inputs.accel] channel = 1" in pane.HELP_TEXT
            await pilot.press("x")

    asyncio.run(scenario())
