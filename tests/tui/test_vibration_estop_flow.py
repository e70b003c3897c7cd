"""Issue 27, fourth new-user try: ctrl+e during a flow is said once on the Vibration
status line, the e-stop's reason whole ("(operator e-stop (console))"), not a second
line with its closing parenthesis stripped."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import command, wait_for, words_on


def test_an_estop_during_a_flow_is_said_once_with_its_reason_whole(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            await command(app, pilot, f"load {map_file}")
            await wait_for(pilot, lambda: pane.session is not None, 30, "map loaded")
            said: list[str] = []
            status = pane.status

            def keep(text: str, *args, **kwargs) -> None:
                said.append(text)
                status(text, *args, **kwargs)

            pane.status = keep
            await command(app, pilot, "14 20")
            line = lambda: words_on(app, "#vib-status")  # noqa: E731
            await wait_for(pilot, lambda: "playing flow" in line(), 60, "flow playing")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: "e-stop" in line(), 30, "said on the status line")
            await wait_for(pilot, lambda: pane._now_playing is None, 30, "play ended")
            await pilot.pause(1.0)  # a late second line would come now
            text = line()
            assert "stopped by the e-stop" in text, text
            assert text.count("(") == text.count(")"), text
            assert len([s for s in said if "e-stop" in s]) == 1, said

    asyncio.run(scenario())
