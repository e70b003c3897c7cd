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


def test_an_estop_between_two_trials_reads_as_one_that_stopped_a_trial():
    """On a loaded machine the shell's e-stop came after a stimulus had ended: the next
    trial's play was refused and the run said `the outputs refused 'flow 52->51': e-stop
    active (...)`; it says the e-stop stopped the run, naming the stimulus once."""
    from types import SimpleNamespace

    from console.core.errors import UserError
    from plugins.studies.stimuli import play_on_session

    why = "refused: e-stop active (haptable estop (pid 4242, user on pts/3)), ctrl+r resets"
    session = SimpleNamespace(play_plan_why=lambda plan, holder=None: why)
    with pytest.raises(UserError) as err:
        play_on_session(session)(SimpleNamespace(name="flow 52->51"))
    text = str(err.value)
    assert "refused" not in text, text
    assert text == (
        "stopped by the e-stop (haptable estop (pid 4242, user on pts/3)) before "
        "'flow 52->51', ctrl+r resets"
    ), text
