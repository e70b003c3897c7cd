"""The Studies screen, issue 27: ``a`` asks before it aborts a participant's run, a
resumed run shows its earlier trials, ``r`` answers in a simulated run; and the CLI
takes the console's word for the analysis (``study analyse`` as ``study analyze``)."""

from __future__ import annotations

import asyncio
import json

import pytest

from console.cli.main import main

from . import synth_runs as sr
from .studies_pilot import studies_app, studies_pane, wait_for


def _done(path):
    lines = [json.loads(x) for x in path.read_text().splitlines() if x.strip()]
    return [e["trial"] for e in lines if e["event"] == "done"]


async def _running(pilot, app, map_file, out):
    """The Studies screen with a simulated exp2 run of P01 going on, two trials done."""
    from textual.widgets import ProgressBar

    pane = await studies_pane(pilot, app, map_file)
    pane.query_one("#protocol").value = "exp2"
    pane.query_one("#out").value = str(out)
    pane.focus()
    await pilot.press("s")
    bar = pane.query_one("#study-progress", ProgressBar)
    await wait_for(pilot, lambda: (bar.progress or 0) >= 2, what="two trials done")
    return pane


def _app(double_plugins):
    return studies_app(double_plugins)


def test_abort_asks_first(double_plugins, map_file, tmp_path, monkeypatch):
    from plugins.studies import panel as studies_panel

    monkeypatch.setattr(studies_panel, "CONFIRM_S", 1.0, raising=False)  # after conftest's

    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _running(pilot, app, map_file, tmp_path)
            status = pane.query_one("#study-status")
            # paused: the simulated participant would finish the 200 trials within the
            # seconds the questions take on a loaded machine (a run that ended has
            # nothing to abort)
            await pilot.press("p")
            await wait_for(pilot, lambda: pane.control.paused, 5, "paused")
            # one a: the run goes on, the status line asks for a second one
            await pilot.press("a")
            await pilot.pause(0.1)
            assert pane.running == "P01"
            assert "a again within 1 s aborts P01's run" in str(status.render())
            # too late: the question goes, and a single a asks again
            await wait_for(pilot, lambda: "a again" not in str(status.render()), 5, "expired")
            await pilot.press("a")
            await pilot.pause(0.1)
            assert pane.running == "P01" and "a again" in str(status.render())
            # a second a in time aborts
            await pilot.press("a")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            assert "aborted" in str(status.render())

    asyncio.run(scenario())


def _says_no_replay(pane) -> bool:
    status = str(pane.query_one("#study-status").render())
    return "simulated" in status and "replay" in status


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_replay_in_a_simulated_run_says_why_not(double_plugins, map_file, tmp_path, size):
    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await _running(pilot, app, map_file, tmp_path)
            await pilot.press("r")
            # the screen's own key: its status says it, no toast (console.tui.said); a
            # bounded wait (a loaded machine draws late), the same assertion
            await wait_for(pilot, lambda: _says_no_replay(pane), 5, "r's answer")
            said = [n.message for n in app._notifications]
            assert not any("simulated" in m for m in said), said
            pane.control.abort("test over")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_keys_answer_outlasts_the_runs_next_trial(double_plugins, map_file, tmp_path, size):
    """A simulated run's next trial starts within milliseconds of ``r``: its answer holds
    the status line for ``ANSWER_HOLD_S`` (progress never replaces it sooner), then
    the run's state moving on takes it."""
    from plugins.studies import panel_status

    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await _running(pilot, app, map_file, tmp_path)
            await pilot.press("r")
            trial = pane.last.get("trial") or {}
            pane._snapshot({"kind": "start", "trial": trial})  # a trial starts at once
            pane._snapshot({"kind": "progress", "done": 3, "total": 200})
            assert _says_no_replay(pane), str(pane.query_one("#study-status").render())
            # held long enough: the next trial's start takes it
            pane.said_at -= panel_status.ANSWER_HOLD_S + 0.1
            pane._snapshot({"kind": "start", "trial": trial})
            assert not _says_no_replay(pane)
            pane.control.abort("test over")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")

    asyncio.run(scenario())


def test_a_resumed_run_shows_its_earlier_trials(double_plugins, map_file, tmp_path):
    from textual.widgets import DataTable, ProgressBar

    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _running(pilot, app, map_file, tmp_path)
            pane.control.abort("stopped by the test")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            table = pane.query_one("#study-trials", DataTable)
            bar = pane.query_one("#study-progress", ProgressBar)
            first = len(_done(tmp_path / "P01" / "trials.jsonl"))
            assert table.row_count == first >= 2
            # resumed: the earlier trials are in the table, then the new ones
            await pilot.press("s")
            await wait_for(pilot, lambda: (bar.progress or 0) >= first + 2, what="resumed")
            pane.control.abort("stopped by the test")
            await wait_for(pilot, lambda: pane.running is None, what="stopped again")
            await pilot.pause(0.2)
            done = _done(tmp_path / "P01" / "trials.jsonl")
            assert table.row_count == len(done) > first
            shown = [str(table.get_row_at(i)[0]) for i in range(table.row_count)]
            assert shown == [str(t + 1) for t in done]

    asyncio.run(scenario())


def test_cli_analyse_is_analyze(tmp_path, capsys):
    root = sr.write_flow(tmp_path / "e", "exp1", ("1", "2"), lambda *a: 1.0, 3, 2)
    assert main(["study", "analyze", str(root), "--json"]) == 0
    us = json.loads(capsys.readouterr().out)
    assert main(["study", "analyse", str(root), "--json"]) == 0
    uk = json.loads(capsys.readouterr().out)
    assert uk == us
