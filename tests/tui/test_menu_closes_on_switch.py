"""An open dropdown closes when the screen changes: F1, the test-signal list opened with
Enter, F2 then F1 left its menu drawn nowhere but focused (the footer said ``esc Dismiss
menu``) and Down then Enter changed the test signal unseen."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Select
from textual.widgets._select import SelectOverlay

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_an_open_menu_closes_with_its_screen(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            stim = app.query_one("#stimulus", Select)
            await wait_for(pilot, lambda: app.focused is not None, 20, "focus")
            stim.focus()
            await pilot.pause()
            await pilot.press("enter")
            await wait_for(pilot, lambda: stim.expanded, 10, "menu open")
            await pilot.press("f2")
            await wait_for(pilot, lambda: app.active_tab == "camera", 20, "camera")
            await pilot.press("f1")
            await wait_for(pilot, lambda: app.active_tab == "devices", 20, "devices")
            await wait_for(pilot, lambda: app.focused is not None, 20, "focus back")
            await pilot.pause(0.2)
            assert not stim.expanded
            assert not isinstance(app.focused, SelectOverlay), app.focused
            # menu closed; the focus comes back to the list the operator left (its menu
            # closed: what Enter or Down does next is seen)
            assert app.focused is stim, app.focused
            await pilot.press("down", "enter")  # Enter opens the menu again, visibly
            await pilot.pause(0.2)
            assert stim.value == "sine-PA"
            assert not stim.expanded or stim.query_one(SelectOverlay).region.height > 0

    asyncio.run(scenario())
