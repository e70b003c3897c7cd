"""A new operator's try (issue 27, newuser7 #6): the flow demo stopped with ``s`` at
120 x 40, then the terminal resized to 80 x 24: the last-run block kept its 120-column
layout, wrapped again by Textual (``scene 0.0…`` cut inside a value, ``end to end``
alone on a row, ``.../demo-17199-flow-2026120…`` cut inside a name), and leaving and
coming back did not lay it out again. The demo status is fitted again whenever its
width changes."""

from __future__ import annotations

import asyncio

from rich.text import Text
from textual.widgets import Static

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_demos import _start


def _rows(status: Static) -> list[str]:
    return str(status.render()).split("\n")


def _fits(status: Static) -> None:
    """Every row of the demo status within its width (Textual wraps none again), the
    twin's log path whole names only."""
    width = status.content_region.width
    rows = _rows(status)
    assert all(Text(r.rstrip()).cell_len <= width for r in rows), (width, rows)
    path = [r for r in rows if "demo-" in r]
    assert path and all(r.rstrip().endswith("json") for r in path), rows


def test_the_last_run_is_laid_out_again_after_a_resize(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await _start(app, pilot, "knob")
            await wait_for(
                pilot,
                lambda: "latency" in str(pane.query_one("#demo-status").render()),
                20,
                "numbers",
            )
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.demo_name is None, 30, "demo stopped")
            await pilot.pause(0.3)
            status = app.query_one("#demo-status", Static)
            assert "last run" in _rows(status)[0]
            _fits(status)
            wide = _rows(status)
            await pilot.resize_terminal(80, 24)
            await pilot.pause(0.3)
            _fits(status)
            assert _rows(status) != wide
            await pilot.press("f1")
            await pilot.pause(0.2)
            await pilot.resize_terminal(120, 40)  # resized while Scenes is hidden
            await pilot.pause(0.2)
            await pilot.press("f6")
            await pilot.pause(0.3)
            _fits(status)
            assert _rows(status) == wide

    asyncio.run(scenario())
