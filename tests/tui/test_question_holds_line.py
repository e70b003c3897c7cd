"""A timed question stays on its status line until it lapses or is answered (a new
operator's try at 80 x 24, Vibration: ``f``, then ``m`` with a kept map; the flow's
``played ...`` replaced the question 3 s later while its 5 s still ran, and a second
``m`` replaced the map with no question on screen). Lines said meanwhile wait: they are
in the log at once and the newest shows when the question lapses
(``console.tui.lapse``)."""

from __future__ import annotations

import asyncio
import logging

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_screens import kept_map_grid, two_points_asked

ASKED = "m again within 5 s measures the grid anew"


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_vibration_question_outlasts_a_play_said_meanwhile(plugins, map_file, size, caplog):
    caplog.set_level(logging.INFO, "haptable.console")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            pane = await kept_map_grid(app, pilot, map_file)
            await two_points_asked(app, pilot, pane, ASKED)
            await pilot.press("f")  # its play ends while the question still counts
            played = lambda: "status Vibration: played flow" in caplog.text  # noqa: E731
            await wait_for(pilot, played, 10, "the play said (in the log)")
            await pilot.pause(0.2)
            assert ASKED in words_on(app, "#vib-status"), "the question left its line early"
            await wait_for(
                pilot, lambda: "played flow" in words_on(app, "#vib-status"), 10, "after"
            )
            assert "again within" not in words_on(app, "#vib-status")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_another_key_pressed_during_a_question_is_answered_at_once(plugins, map_file, size):
    """The question keeps the line, and the other key's answer is not kept back for
    the question's 5 s: it shows at once as a toast (a key must say something)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            pane = await kept_map_grid(app, pilot, map_file)
            await two_points_asked(app, pilot, pane, ASKED)
            before = len(app._notifications)
            await pilot.press("f")

            def toasts() -> list[str]:
                shown = list(app._notifications)[before:]
                return [n.message for n in shown if "flow" in n.message]

            await wait_for(pilot, lambda: bool(toasts()), 3, "f's answer as a toast")
            assert ASKED in words_on(app, "#vib-status"), "the question left its line"

    asyncio.run(scenario())
