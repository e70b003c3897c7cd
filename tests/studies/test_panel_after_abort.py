"""The Studies screen after an abort (issue 27, third new-user try): the last key's
"resumed" goes with the run; the help shows ``n / Analyse`` on a line of its own."""

from __future__ import annotations

import asyncio

from .studies_pilot import wait_for
from .test_panel_issue27 import _app, _running


def _status(pane) -> str:
    return " ".join(str(pane.query_one("#study-status").render()).split())


def test_resumed_goes_when_the_run_is_aborted(double_plugins, map_file, tmp_path):
    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _running(pilot, app, map_file, tmp_path)
            await pilot.press("p")
            await pilot.press("p")
            await wait_for(pilot, lambda: "resumed" in _status(pane), 30, "resumed")
            await pilot.press("a", "a")
            await wait_for(pilot, lambda: pane.running is None, 30, "the run stopped")
            await wait_for(pilot, lambda: "stopped: aborted" in _status(pane), 30, "aborted")
            assert "resumed" not in _status(pane)

    asyncio.run(scenario())


def test_the_help_shows_analyse_apart_from_abort():
    from console.tui.help import paragraphs
    from plugins.studies.panel import StudiesPane

    lines = paragraphs(StudiesPane.HELP_TEXT)
    assert any(line.startswith("n / Analyse ") for line in lines)
    abort = next(line for line in lines if line.startswith("a "))
    assert "Analyse" not in abort
