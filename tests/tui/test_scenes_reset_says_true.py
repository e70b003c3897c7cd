"""After the e-stop's reset, the Scenes screen's line about a demo the e-stop refused is
true (a new operator's try at 80 x 24): a knob that never ran was said to start `again`."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_demo_that_never_ran_is_not_said_to_start_again(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 30, "e-stopped")
            demos = app.query_one("#demo-table", DataTable)
            await pilot.press("d")
            await wait_for(pilot, lambda: app.focused is demos, 10, "the demos list")
            await pilot.press("down", "enter")  # the knob, refused: the e-stop is active
            said = lambda: app.query_one("#demo-work").text  # noqa: E731
            await wait_for(pilot, lambda: "e-stop is active" in said(), 20, "refused")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: "e-stop is reset" in said(), 20, "the reset said")
            assert said() == "demo knob: the e-stop is reset; enter starts it", said()
            assert str(demos.get_cell("knob", "state")) == "idle"

    asyncio.run(scenario())
