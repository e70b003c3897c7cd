"""Studies (F10), a new operator's try at 80 x 24 and 120 x 40: the protocol drop-down
offers the protocols only (no blank "Select" entry): Down past the last one wraps to the
first, never to a choice named ``Select.NULL``; the folder follows the protocol chosen,
and ``s`` starts the protocol shown."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Select

from console.cli.main import Context
from console.tui.app import HapTableApp
from plugins.studies import protocol as protocols

from ..studies.studies_pilot import studies_idle
from .conftest import wait_for, words_on
from .test_camera_layout import SIZES


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_protocol_list_has_no_blank_choice_and_the_folder_follows(plugins, size):
    names = protocols.available()

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            pane = await studies_idle(app, pilot)
            status = lambda: words_on(app, "#study-status")  # noqa: E731
            select = pane.query_one("#protocol", Select)
            select.focus()
            await pilot.press("enter")  # the list open
            await wait_for(pilot, lambda: select.expanded, 10, "the list open")
            for _ in range(len(names)):  # past the last: wraps to the top entry
                await pilot.press("down")
            await pilot.press("enter")
            await wait_for(pilot, lambda: not select.expanded, 10, "the list closed")
            await pilot.pause(0.2)
            folder = pane.query_one("#out").value
            assert select.value in names, select.value
            assert "Select" not in status() and "NULL" not in folder, (status(), folder)
            assert folder.endswith(f"/{select.value}"), folder
            # another protocol: the folder follows it
            select.value = "threshold_vibrotactile"
            await wait_for(
                pilot,
                lambda: pane.query_one("#out").value.endswith("/threshold_vibrotactile"),
                10,
                "the folder following the protocol",
            )
            assert "threshold_vibrotactile chosen" in status(), status()

    asyncio.run(scenario())
