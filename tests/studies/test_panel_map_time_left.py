"""The Studies screen's vibration-map step says the time it still needs, as the other
long steps do (issue 27: "vibration map: measuring ..." with a bar and no end in sight),
at 80 x 24 and 120 x 40."""

from __future__ import annotations

import asyncio

import pytest

from .studies_pilot import pick_protocol, studies_pane, wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_map_measurement_says_the_time_left(
    double_plugins, tmp_path, small_exp2, size, monkeypatch
):
    from textual.widgets import Static

    from plugins.studies import panel_status

    # the step's clock a second on per progress report: the twin's map can take about a
    # second on a quiet machine, too short for any estimate (``time_left.MIN_ELAPSED_S``);
    # what is tested is that the pace the step reports reaches the status line
    ticks = iter(range(10_000))
    real = panel_status.map_state
    monkeypatch.setattr(
        panel_status, "map_state", lambda last, d: real(last, d, clock=lambda: next(ticks))
    )

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
