"""Issue 27: the Vibration screen's footer names its two main actions, enter (audition
the point under the cursor) and ``:`` (the command line), first: at 120 x 40 with every
other key of the screen, at 80 x 24 before the keys that no longer fit. What the footer
says is read from the footer as drawn, and the keys do what it says."""

from __future__ import annotations

import asyncio

from textual.widgets import Footer, Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import text_in


def test_the_vibration_footer_shows_enter_and_colon_first_at_both_sizes(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("vibration")
            grid = pane.focus_target
            await wait_for(pilot, lambda: app.focused is grid, 30, "the grid focused")

            def footer() -> str:
                return text_in(app, app.screen.query_one(Footer))

            await wait_for(pilot, lambda: "E-STOP" in footer(), 30, "the footer drawn")
            await wait_for(pilot, lambda: "audition" in footer(), 10, "enter in the footer")
            said = footer()
            assert said.startswith("⏎ audition : command "), said
            assert "w a s d hand" in said, said  # the hand keys still fit, as one entry
            await pilot.resize_terminal(120, 40)
            await wait_for(pilot, lambda: "x cancel" in footer(), 10, "the footer at 120")
            said = footer()
            assert said.startswith("⏎ audition : command f r flow/back w a s d hand"), said
            for key in ("m measure", "b tables", "x cancel", "E-STOP", "? help"):
                assert key in said, (key, said)
            # the keys do what the footer says: enter auditions the point under the
            # cursor (without a map the status line says how to get one), ":" opens the
            # command line
            await pilot.press("enter")

            def answered() -> bool:
                said = pane.status_text
                return "no vibration map yet" in said or "point" in said

            await wait_for(pilot, answered, 10, "enter answered")
            await pilot.press("colon")
            await wait_for(pilot, lambda: isinstance(app.focused, Input), 10, "the command line")

    asyncio.run(scenario())
