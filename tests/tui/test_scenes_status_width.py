"""Scenes' demo lines use the width they have and go to the log whole (issue 27: at
120 columns ``flow right: 1 played…``, ``flow loop stopped 10 s …`` and ``the twin's
outputs received: /tmp/…/demo-…json`` were cut, and none was in console.log)."""

from __future__ import annotations

import asyncio
import logging

import pytest
from textual.widgets import Static

from console.cli.main import Context
from console.tui import said
from console.tui.app import HapTableApp

from .conftest import wait_for

LINE = "flow right: 1 played, 0 refused  latency 12.3 ms (p95 14.1 ms)  drops 0, late 0"


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_demo_line_uses_its_width_and_is_logged_whole(plugins, size, caplog, monkeypatch):
    # the log says a screen's line once (not again within 30 s): this test's console new
    monkeypatch.setattr(said, "_last_status", {})

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 20, "Scenes")
            pane = app.pane("scenes")
            status = app.query_one("#demo-status", Static)
            text = LINE + "; last at 120,45 mm: PA 160 Hz + PB 200 Hz (planned in 12 ms)"
            with caplog.at_level(logging.INFO, "haptable.console"):
                pane._show_last_run(text)
                await pilot.pause(0.3)
            shown = str(status.render())
            rows = shown.split("\n")
            assert all(len(r.rstrip()) <= status.content_region.width for r in rows), rows
            if size[1] > 24:  # rows to spare: the line whole, wrapped between fields
                assert "…" not in shown, rows
                assert " ".join(" ".join(rows).split()) == " ".join(text.split()), rows
            else:  # one row: whole fields dropped
                assert len(rows) == 1, rows
            whole = " ".join(text.split())  # the log's spacing
            assert any(whole in r.getMessage() for r in caplog.records), "not in the log whole"

    asyncio.run(scenario())
