"""The Studies screen, opened, shows the chosen protocol's saved progress of the chosen
participant in the chosen folder (bar, status, trials table), as another choice does,
also when the run was saved while the console showed another screen (`haptable study
run` in a shell), not the idle status over a run half done (a new operator's try)."""

from __future__ import annotations

import asyncio

import pytest

from .studies_pilot import studies_app, studies_pane, wait_for


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """The protocols' default folder (the one the screen opens with) in ``tmp_path``."""
    from plugins.studies import panel, panel_choice

    out = tmp_path / "results"
    monkeypatch.setattr(panel, "default_out", lambda study="": out)
    monkeypatch.setattr(panel_choice, "default_out", lambda study="": out)
    return out


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_screen_opens_on_the_saved_progress(double_plugins, map_file, folder, size):
    from textual.widgets import ProgressBar, Static

    async def half_run():  # P01's exp1 run, stopped after two trials
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            assert pane.query_one("#protocol").value == "exp1"
            pane.focus()
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.last.get("done", 0) >= 2, what="two trials")
            await pilot.press("a", "a")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            return pane.last["done"]

    async def opened_again(done: int):
        from console.cli.main import Context
        from console.tui.app import HapTableApp  # lazy: the console loads with the pilot

        app = HapTableApp(Context("sim", double_plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            await pilot.press("f10")  # seen once: nothing saved yet
            pane = await studies_pane(pilot, app, map_file)
            await wait_for(
                pilot,
                lambda: "no study running" in str(pane.query_one("#study-status").render()),
                10,
                "idle",
            )
            await pilot.press("f1")
            await pilot.pause(0.5)
            aside.rename(folder)  # the run saved meanwhile (a shell's `haptable study run`)
            await pilot.press("f10")
            table = pane.query_one("#study-trials")
            status = pane.query_one("#study-status", Static)
            await wait_for(pilot, lambda: table.row_count == done, 10, "P01's trials")
            text = " ".join(str(status.render()).split())
            assert f"P01: {done}/50 trials done" in text, text
            assert f"s resumes P01 at trial {done + 1} of 50" in text, text
            bar = pane.query_one("#study-progress", ProgressBar)
            assert bar.progress == done and bar.total == 50

    done = asyncio.run(half_run())
    assert (folder / "P01" / "trials.jsonl").exists()
    aside = folder.with_name("aside")
    folder.rename(aside)
    asyncio.run(opened_again(done))
