"""The Studies screen after an e-stop stopped a run: once the operator resets it
(ctrl+r), the line that said the e-stop stopped the run and that ctrl+r resets it says
the reset instead (as Devices, Electrostatic, Signals and Scenes do); a new e-stop
brings back the line saying it is active."""

from __future__ import annotations

import asyncio

import pytest

from .studies_pilot import exp1_trial_done, studies_app, studies_pane, wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_reset_replaces_the_line_the_e_stop_left(double_plugins, map_file, tmp_path, size):
    from textual.widgets import Static

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            status = pane.query_one("#study-status", Static)
            await exp1_trial_done(pilot, pane, tmp_path)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            await wait_for(pilot, lambda: "ctrl+r resets" in str(status.render()), 10)
            done = pane.last["done"]
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            await wait_for(pilot, lambda: "e-stop reset" in str(status.render()), 10)
            text = str(status.render())
            assert "ctrl+r resets" not in text and "e-stop active" not in text
            assert f"e-stop reset: s resumes P01 at trial {done + 1} of 50" in text
            await pilot.press("ctrl+e")  # latched again: the reset is no longer true
            await wait_for(pilot, lambda: "e-stop reset" not in str(status.render()), 10)
            assert "ctrl+r resets" in str(status.render())
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")

    asyncio.run(scenario())
