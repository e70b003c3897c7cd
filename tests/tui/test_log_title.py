"""The log view's first line at 80 columns: its key first and the log file's whole path
(a long home's path pushed "closes" off the row: `console.log): escape`)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.logs import LogScreen

from .conftest import wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_log_names_its_key_and_its_whole_file(plugins, size, tmp_path, monkeypatch):
    state = tmp_path / "a-lab-member-s-home" / "with-a-long-name" / ".local" / "state"
    monkeypatch.setenv("HAPTABLE_STATE_DIR", str(state / "haptable"))

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("ctrl+l")
            await wait_for(pilot, lambda: isinstance(app.screen, LogScreen), 10, "the log")
            await pilot.pause(0.3)
            rows = [s.text for s in app.screen._compositor.render_strips()]
            shown = "".join(r.strip() for r in rows[1:5])  # under the title row
            assert "escape closes" in rows[1]
            assert str(state / "haptable" / "console.log").replace(" ", "") in shown, rows[:5]

    asyncio.run(scenario())
