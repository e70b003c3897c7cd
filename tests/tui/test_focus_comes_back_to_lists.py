"""A screen gives the focus back to the control the operator left it on (a new operator's
try at 80 x 24): F6, d, the knob started, F7 then F6 again, the footer named the scenes
table's Enter (`⏎ start scene`) and Enter showed a scene over the running demo instead
of stopping it. Lists, tables and buttons are come back to as text fields are; the
screen's own widget takes the focus when that control is gone or hidden."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for

SIZES = [(80, 24), (120, 40)]


def _footer(app) -> str:
    return app.screen._compositor.render_strips()[-1].text


async def _away_and_back(app, pilot, away: str, back: str, tab: str) -> None:
    await pilot.press(away)
    await wait_for(pilot, lambda: app.active_tab != tab, 20, "another screen")
    await wait_for(pilot, lambda: app.focused is not None, 20, "its focus")
    await pilot.press(back)
    await wait_for(pilot, lambda: app.active_tab == tab, 20, f"{tab} again")
    await wait_for(pilot, lambda: app.focused is not None, 20, "the focus back")
    await pilot.pause(0.3)  # the footer follows the focus at the next refresh


@pytest.mark.parametrize("size", SIZES)
def test_the_demos_list_has_the_focus_again_and_its_enter_in_the_footer(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 30, "scenes")
            scenes = app.query_one("#scene-table", DataTable)
            await wait_for(pilot, lambda: app.focused is scenes, 30, "the scenes on entry")
            demos = app.query_one("#demo-table", DataTable)
            await pilot.press("d", "down")
            await wait_for(pilot, lambda: app.focused is demos, 10, "the demos list")
            await _away_and_back(app, pilot, "f7", "f6", "scenes")
            assert app.focused is demos, app.focused
            assert demos.cursor_row == 1  # the knob, as left
            assert _footer(app).strip().startswith("⏎ start/stop demo"), _footer(app)

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES)
def test_devices_comes_back_to_the_list_left_unless_it_is_hidden(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            cards = app.query_one("#audio-table", DataTable)
            await wait_for(pilot, lambda: app.focused is cards, 30, "the sound cards")
            doctor = app.query_one("#device-table", DataTable)
            doctor.focus()
            await wait_for(pilot, lambda: app.focused is doctor, 10, "the doctor's table")
            await _away_and_back(app, pilot, "f4", "f1", "devices")
            assert app.focused is doctor, app.focused
            # gone from view while away: the screen's own list instead
            await pilot.press("f4")
            await wait_for(pilot, lambda: app.active_tab == "relays", 20, "relays")
            doctor.display = False
            await pilot.press("f1")
            await wait_for(pilot, lambda: app.active_tab == "devices", 20, "devices")
            await wait_for(pilot, lambda: app.focused is cards, 20, "the sound cards")

    asyncio.run(scenario())
