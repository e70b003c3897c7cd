"""Issue 27 (a new-user try): an e-stop from a shell (``haptable estop``) stopping a
study run's trial is said as the console's own ctrl+e is: the trial stopped by the
e-stop (not refused, its stimulus named once), and ctrl+r's reset says where ``s``
goes on (``e-stop reset: s resumes P01 at trial N of 50``)."""

from __future__ import annotations

import asyncio

import pytest

from .studies_pilot import exp1_trial_done, studies_app, studies_pane, wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_shell_s_estop_reads_as_the_console_s(double_plugins, map_file, tmp_path, size):
    from textual.widgets import Static

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            status = pane.query_one("#study-status", Static)
            await exp1_trial_done(pilot, pane, tmp_path)
            await wait_for(pilot, lambda: "playing" in str(status.render()), 20, "a stimulus")
            app.session.outputs.estop("haptable estop (pid 4242, user on pts/3)")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            await wait_for(pilot, lambda: "ctrl+r resets" in str(status.render()), 10)
            text = " ".join(str(status.render()).split())
            assert "refused" not in text, text
            assert "stopped by the e-stop" in text and "pid 4242" in text, text
            name = text.split("'")[1] if "'" in text else ""
            assert name and text.count(name) == 1, text  # the stimulus named once
            done = pane.last["done"]
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            await wait_for(pilot, lambda: "e-stop reset" in str(status.render()), 10)
            text = str(status.render())
            assert f"e-stop reset: s resumes P01 at trial {done + 1} of 50" in text, text

    asyncio.run(scenario())
