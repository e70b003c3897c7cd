"""The Gestures panel's ``s`` says whether the synthesis replaces the dataset already in
its folder or makes a new one, and does what it said (new operator's try: the size and
time were offered with no word about the dataset there, which ``s`` again replaced)."""

from __future__ import annotations

import asyncio
import re
import shutil

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import text_in


@pytest.fixture(scope="module")
def tiny_dataset(tmp_path_factory):
    from plugins.gestures.jobs import synth_atomic

    path = tmp_path_factory.mktemp("gestures") / "tiny"
    synth_atomic(path, 1, 2, workers=1)  # 1 subject x 10 gestures x 2 reps
    return path


def _samples(path) -> int | None:
    from plugins.gestures.jobs import describe_files

    return describe_files(path, None)["dataset"].get("samples")


async def _panel(app, pilot, plugins, ds):
    await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
    app.push_screen(plugins.of("panel")["gestures"].factory(app))
    await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel", 30, "panel")
    panel = app.screen
    await wait_for(pilot, lambda: bool(panel.query("#gp-files")), 30, "panel composed")
    panel.query_one("#gp-dataset", Input).value = str(ds)
    panel.query_one("#gp-subjects", Input).value = "1"
    panel.query_one("#gp-reps", Input).value = "1"
    return panel


async def _estimate(pilot, panel) -> str:
    panel.work.outcome = None
    await pilot.press("s")
    await wait_for(pilot, lambda: panel.work.outcome is not None, 60, "estimate")
    return " ".join(panel.work.text.split())


def _whole(app, panel, text: str) -> bool:
    return re.sub(r"\s+", "", text) in re.sub(r"\s+", "", text_in(app, panel.work))


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_s_says_it_replaces_the_dataset_there_and_does(plugins, tmp_path, tiny_dataset, size):
    ds = tmp_path / "set"
    shutil.copytree(tiny_dataset, ds)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            panel = await _panel(app, pilot, plugins, ds)
            asked = await _estimate(pilot, panel)
            assert asked.startswith("s again within"), asked
            assert "replaces the 20 samples" in asked and "not added to" in asked, asked
            await wait_for(pilot, lambda: _whole(app, panel, asked), 10, text_in(app, panel.work))
            if size != (80, 24):
                return
            await pilot.press("s")
            await wait_for(pilot, lambda: panel.work.outcome is not None, 120, "synthesis")
            assert panel.work.outcome == "done", panel.work.text
            assert _samples(ds) == 10  # replaced, not added to

    asyncio.run(scenario())


def test_s_into_a_new_folder_says_so_and_never_replaces_what_came_there(
    plugins, tmp_path, tiny_dataset
):
    ds = tmp_path / "set"

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            panel = await _panel(app, pilot, plugins, ds)
            asked = await _estimate(pilot, panel)
            assert "a new dataset" in asked and "replaces" not in asked, asked
            shutil.copytree(tiny_dataset, ds)  # a dataset written there meanwhile
            await pilot.press("s")
            await wait_for(pilot, lambda: panel.work.outcome is not None, 60, "refused")
            said = " ".join(panel.work.text.split())
            assert panel.work.outcome != "done" and "s says" in said, said
            assert _samples(ds) == 20  # kept

    asyncio.run(scenario())


def test_s_into_a_folder_of_other_files_is_refused_before_measuring(plugins, tmp_path):
    ds = tmp_path / "recorded"
    ds.mkdir()
    (ds / "notes.txt").write_text("a recorded session\n")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            panel = await _panel(app, pilot, plugins, ds)
            said = await _estimate(pilot, panel)
            assert "s again" not in said and "not a synthesized dataset" in said, said
            assert "choose another dataset folder" in said, said
            assert (ds / "notes.txt").is_file()

    asyncio.run(scenario())
