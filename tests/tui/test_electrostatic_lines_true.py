"""Electrostatic's status line stays true and names its fix (a new operator's try): at
720 Hz square, `]` to the slew limit said `... the most a square at 730 Hz may have ...`,
and `t` (to sine) left that line; `p` then `ctrl+e` said `... stopped by the e-stop
(operator e-stop (console))` without `ctrl+r resets`, which the README promises."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_screens import _ready


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_limit_line_goes_with_t_and_an_estop_line_names_ctrl_r(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="electrostatic")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            pane = app.pane("electrostatic")
            line = lambda: words_on(app, "#es-status")  # noqa: E731
            pane.freq_hz = 720.0
            for _ in range(12):
                await pilot.press("plus")
            await pilot.press("t")  # square
            assert pane.waveform == "square"
            await pilot.press("right_square_bracket")  # 730 Hz: past the square's slew limit
            await wait_for(pilot, lambda: "a square at 730 Hz may have" in line(), 10, "limit")
            await pilot.press("t")  # a sine: the square's limit is not true of it
            assert pane.waveform == "sine"
            await wait_for(pilot, lambda: "square" not in line(), 5, "the square's line gone")
            await pilot.press("p")
            await wait_for(pilot, lambda: "playing" in pane.status_text, 10, "playing")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: "stopped by" in line(), 10, "stopped")
            assert "ctrl+r resets, then p plays" in line(), line()
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: "e-stop reset" in line(), 10, "reset said")

    asyncio.run(scenario())
