"""The quit prompt names each thing that would stop once (issue 27, third new-user try):
a demo still starting is its LongWork and the session's run, one demo."""

from __future__ import annotations

import asyncio
from types import SimpleNamespace

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def test_the_quit_prompt_names_a_starting_demo_once(plugins, monkeypatch):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 30, "scenes")
            demos, work = app.session.demos, app.query_one("#demo-work")
            # as while the flow demo prepares: its process runs, its start's work too
            run = SimpleNamespace(stopped=False, snapshot=lambda: {"demo": "flow"})
            monkeypatch.setattr(demos, "run", run)
            monkeypatch.setattr(demos, "name", "flow")
            monkeypatch.setattr(work, "name_running", "demo flow")
            await pilot.press("q")
            await pilot.pause(0.3)
            shown = [str(n.message) for n in app._notifications]
            assert "q again within 3 s quits, stopping the flow demo" in shown, shown
            monkeypatch.setattr(demos, "run", None)  # nothing left to stop on the way out
            monkeypatch.setattr(work, "name_running", None)

    asyncio.run(scenario())
