"""A new operator's try (Signals, F8): ``sine(250 Hz, 20 V, 99999 s)`` was refused as
``1e+05 s is longer than ...``; the status line says the duration as typed."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_screens import _ready


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_signals_says_a_long_duration_as_typed(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            box = app.query_one("#sig-expr", Input)
            box.value = "sine(250 Hz, 20 V, 99999 s) * ramp(20 ms)"
            await pilot.press("enter")
            said = lambda: "longer than" in words_on(app, "#sig-status")  # noqa: E731
            await wait_for(pilot, said, 10, "refused")
            line = words_on(app, "#sig-status")
            assert "99999 s is longer than" in line and "e+" not in line, line

    asyncio.run(scenario())
