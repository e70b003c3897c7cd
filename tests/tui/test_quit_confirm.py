"""q quits at once when nothing runs; while work runs (a demo, long work, a study run)
it says what would stop and quits only on a second q."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def test_q_asks_again_while_work_runs_and_quits_at_once_otherwise(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("studies")
            await wait_for(pilot, lambda: app.focused is not None, what="focus")
            pane.running = "P01"  # as while a participant's run is under way
            assert app.work_under_way() == ["P01's study run"]
            await pilot.press("q")
            await pilot.pause(0.3)
            assert app.is_running  # the first q asked
            shown = [str(n.message) for n in app._notifications]
            assert any("q again within 3 s quits, stopping P01's study run" in m for m in shown)
            await pilot.press("q")
            await wait_for(pilot, lambda: not app.is_running, 10, "quit on the second q")

    asyncio.run(scenario())


def test_q_quits_at_once_when_nothing_runs(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.focused is not None, what="focus")
            assert app.work_under_way() == []
            await pilot.press("q")
            await wait_for(pilot, lambda: not app.is_running, 10, "quit")

    asyncio.run(scenario())
