"""Studies (F10) at 80 x 24 and 120 x 40: a folder typed that is a file is refused as
typed and at Enter, naming it, and nothing of the folder before stays shown (it was
refused only at ``s``, the old folder's run still on screen)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from ..studies.studies_pilot import studies_idle
from .conftest import wait_for, words_on
from .test_camera_layout import SIZES


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_a_folder_that_is_a_file_is_refused_at_enter(plugins, size, tmp_path):
    afile = tmp_path / "notes.txt"
    afile.write_text("not a folder\n")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            pane = await studies_idle(app, pilot)
            status = lambda: words_on(app, "#study-status")  # noqa: E731
            field = pane.query_one("#out", Input)
            field.focus()
            await wait_for(pilot, lambda: field.has_focus, 5, "the folder field")
            field.value = ""
            await pilot.press(*str(afile))
            await pilot.press("enter")
            await wait_for(pilot, lambda: "not a folder" in status(), 5, "refused at Enter")
            assert "notes.txt" in status(), status()
            assert pane.query_one("#study-trials").row_count == 0

    asyncio.run(scenario())
