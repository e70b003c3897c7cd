"""A second new operator's try: Devices `t` plays "the chosen test signal", but neither
`?` nor the screen said how to choose one (only sine-PA ever played). The heading above
the drop-down says it, and the help's `t` line too; Tab reaches it and enter lists them."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Select

from console.runtime.context import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_screen_says_how_to_choose_the_test_signal(plugins, size):
    from console.tui.panes.devices import TEST_SIGNAL_HEADING, DevicesPane

    assert "Tab to the drop-down, enter lists the signals" in DevicesPane.HELP_TEXT

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            chooser = app.query_one("#stimulus", Select)
            for _ in range(12):  # Tab reaches the drop-down
                if chooser.has_focus:
                    break
                await pilot.press("tab")
            assert chooser.has_focus
            await wait_for(
                pilot, lambda: TEST_SIGNAL_HEADING in "\n".join(screen_lines(app)), 10, "heading"
            )
            assert len(TEST_SIGNAL_HEADING) <= size[0] - 2

    asyncio.run(scenario())
