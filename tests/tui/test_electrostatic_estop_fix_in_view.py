"""What the operator must act on is on screen: a long e-stop reason on Electrostatic's
status line at 80 x 24 was cut at the bottom (``... the machine is overloaded (load
average``), its fix ``close other programs before resetting`` off screen and out of
reach (new operator's report, finding 5). The status line keeps its rows whole; the
list and the setting above it give way (the list scrolls within itself)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.runtime.watchdog import stall_reason
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_question_in_view import _screen_text


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_long_estop_reason_shows_whole_with_its_fix(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="electrostatic")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            pane = app.pane("electrostatic")
            await pilot.press("end")  # the list's last item highlighted
            await pilot.press("p")  # a 1 s play, stopped by the watchdog's e-stop
            await wait_for(pilot, lambda: "playing" in pane.status_text, 10, "playing")
            app.session.estop(stall_reason(0.255, "camera", 0.25, load=(3.4, 2)))
            await wait_for(pilot, lambda: "stopped by" in pane.status_text, 10, "stopped")
            await pilot.pause(0.3)
            shown = _screen_text(app)
            assert "close other programs before resetting" in shown, shown
            assert "close other programs before resetting" in pane.status_text
            last = app.query_one("#es-list").highlighted_option.prompt
            head = " ".join(str(last).split()[:3])  # its first words (the rest may wrap)
            assert f"▊ {head}" in shown, shown  # the list gave way, its cursor in view

    asyncio.run(scenario())
