"""The Camera screen (F2) keeps the chosen setting's row (``▸ body_threshold``) in view
while the answer to a tuning key shows, at 80 x 24 and 120 x 40: ``T`` pressed until a
step is refused (the thresholds' order) and ``W``'s question each take the status line,
and the row they answer about stays on the screen beside them."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera_chosen_under_status import _row
from .test_camera_layout import SIZES, _first_frame


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_chosen_row_stays_with_a_refusal_and_w(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            said = lambda: words_on(app, "#camera-status")  # noqa: E731
            for _ in range(20):
                await pilot.press("T")
            await wait_for(pilot, lambda: "R: the profile" in said(), 10, "the refusal")
            await pilot.pause(0.6)  # the live numbers' next write
            assert app.pane("camera").chosen_key() == "body_threshold"
            assert _row(app, "body_threshold") is not None, said()
            await pilot.press("W")
            await wait_for(pilot, lambda: "W again within" in said(), 10, "W asks")
            await pilot.pause(0.6)
            assert _row(app, "body_threshold") is not None, said()
            assert "W again within" in said()

    asyncio.run(scenario())
