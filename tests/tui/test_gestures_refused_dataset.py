"""Gestures panel (Camera ``g``), a new operator's try at 80 x 24 and 120 x 40: a file
typed as the dataset is refused in one account: the work line and the files block agree
(the block never offers ``s`` for a path ``s`` refuses), and so of a folder typed as the
model (never offering ``t``)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import SIZES, text_in


async def _panel(app, pilot, plugins):
    await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
    app.push_screen(plugins.of("panel")["gestures"].factory(app))
    await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel", 30, "panel")
    panel = app.screen
    await wait_for(pilot, lambda: bool(panel.query("#gp-files")), 30, "panel composed")
    return panel


async def _type(pilot, panel, wid: str, text: str) -> None:
    field = panel.query_one(f"#{wid}", Input)
    field.focus()
    await pilot.pause()
    field.value = ""
    await pilot.press(*text)


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_a_file_as_dataset_is_refused_in_one_account(plugins, tmp_path, size):
    afile = tmp_path / "passwd"
    afile.write_text("root:x:0:0\n")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            panel = await _panel(app, pilot, plugins)
            await _type(pilot, panel, "gp-dataset", str(afile))
            await _type(pilot, panel, "gp-subjects", "2")
            await _type(pilot, panel, "gp-reps", "3")
            await pilot.press("enter")  # back to the buttons: the files block follows
            await pilot.press("s")
            work = panel.work
            await wait_for(pilot, lambda: "not a folder" in work.text, 30, "refused")
            files = lambda: " ".join(text_in(app, panel.query_one("#gp-files")).split())  # noqa: E731
            await wait_for(pilot, lambda: "not a folder" in files(), 30, f"block: {files()}")
            assert "s synthesizes" not in files(), files()
            await pilot.press("t")  # training says the same of it
            await wait_for(pilot, lambda: "not a folder" in work.text, 30, "t refused")
            assert "s synthesizes" not in work.text, work.text
            # a folder as the model: refused by t, and the block says so (not "t trains")
            await _type(pilot, panel, "gp-dataset", str(tmp_path / "set"))
            await _type(pilot, panel, "gp-model", str(tmp_path))
            await pilot.press("enter")
            await wait_for(pilot, lambda: "is a folder" in files(), 30, f"block: {files()}")
            assert "t trains" not in files(), files()

    asyncio.run(scenario())
