"""Relays (F4): a toggle refused because another process's run holds the outputs says
who holds them, whole: what to stop and its pid in view at 80 x 24, no word cut at the
row's edge (the row kept the one row its earlier text took and cut the holder's pid and
name at 80 columns; issue 27)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import text_in

#: how a study run started in a shell names itself in the table's hold file
SHELL_RUN = "a simulated study run of exp1 (haptable study run --simulate, pid 424242)"


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_refusal_names_the_holding_run_whole(plugins, monkeypatch, size):
    import console.session.core as core

    monkeypatch.setattr(core, "table_holder", lambda profile: SHELL_RUN)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            row = app.query_one("#interlock-1")
            await wait_for(pilot, lambda: text_in(app, row).startswith("open"), 30, "row")
            await pilot.press("1")
            await wait_for(pilot, lambda: "refused" in text_in(app, row), 30, "refused")
            await pilot.pause(0.3)
            shown = text_in(app, row)
            # what to stop and its pid, every word of the row whole
            for words in ("study run of exp1", "pid 424242", "stop it there"):
                assert words in shown, shown
            assert shown == " ".join(str(row.render()).split()), shown  # nothing cut off
            assert row.region.right <= app.screen.region.right, row.region

    asyncio.run(scenario())
