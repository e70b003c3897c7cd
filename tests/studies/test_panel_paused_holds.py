"""Issue 27 (a new-user try): a paused study run still holds the outputs (it resumes
where it stopped, nothing else may take them meanwhile), so Devices' ``t`` refused
during the pause must not advise pausing: the refusal says what is true, stop it."""

from __future__ import annotations

import asyncio

import pytest

from .studies_pilot import studies_app, studies_pane, wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_paused_run_s_refusal_advises_no_pause(double_plugins, map_file, tmp_path, size):
    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            pane.query_one("#protocol").value = "exp1"
            pane.query_one("#out").value = str(tmp_path)
            pane.query_one("#participant").value = "P01"
            pane.focus()
            await pilot.press("s")
            await wait_for(pilot, lambda: app.session.outputs_holder is not None, 30, "held")
            await pilot.press("p")
            await wait_for(pilot, lambda: pane.control.paused, 10, "paused")
            await pilot.press("f1")
            devices = app.pane("devices")
            await wait_for(pilot, lambda: devices is not None or app.pane("devices"), 20)
            devices = app.pane("devices")
            await wait_for(pilot, lambda: app.focused is not None, 10, "focus")
            await pilot.press("t")
            await wait_for(pilot, lambda: "holds the outputs" in devices.result, 20, "refused")
            said = " ".join(devices.result.split())
            assert app.session.outputs_holder is not None  # paused: still held
            assert "pause or" not in said and "pause it" not in said, said  # no false advice
            assert "holds the outputs, paused or not (stop it first)" in said, said
            await pilot.press("f10")
            await pilot.pause(0.2)
            pane.focus()
            await pilot.press("a", "a")
            await wait_for(pilot, lambda: pane.running is None, 30, "the run stopped")

    asyncio.run(scenario())
