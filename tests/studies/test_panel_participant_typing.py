"""A participant typed that cannot name a folder (a space, a slash) is refused on the
status line as it is typed, and the console goes on (a new operator typed ``P 0/`` in
the participant field and the console closed with a traceback)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from .studies_pilot import studies_app, studies_pane, wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_participant_that_cannot_be_a_folder_is_refused_as_typed(double_plugins, size):
    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app)
            pane.query_one("#protocol").value = "exp1"
            field = pane.query_one("#participant", Input)
            field.focus()
            await wait_for(pilot, lambda: app.focused is field, 30, "participant focused")
            field.value = ""
            for key in ("P", "space", "0", "slash"):
                await pilot.press(key)
            await pilot.pause(0.2)
            assert app.is_running and field.value == "P 0/"
            status = pane.query_one("#study-status")
            line = str(status.render())
            assert "participant 'P 0/'" in line and "e.g. P01" in line, line
            # made right again: the refusal goes, the choice is shown
            field.value = "P01"
            await wait_for(pilot, lambda: "'P 0/'" not in str(status.render()), 10, "gone")
            assert app.is_running

    asyncio.run(scenario())
