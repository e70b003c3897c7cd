"""The Studies screen says what is true (issue 27): ``a`` with no run says there is
nothing to abort; a number field refuses what it does not take, naming the field; a
start refused is worded as a refusal (nothing was stopped); Escape leaves a text field
with what was typed; ``p`` says "pausing after this trial" until the run is paused."""

from __future__ import annotations

import asyncio

from textual.widgets import Input

from .studies_pilot import studies_app, studies_pane, wait_for
from .test_panel_issue27 import _running


def _app(double_plugins):
    return studies_app(double_plugins)


def _status(pane) -> str:
    return str(pane.query_one("#study-status").render())


async def _pane(pilot, app):
    return await studies_pane(pilot, app)


def test_a_without_a_run_and_a_bad_age_say_so_in_one_line(double_plugins, tmp_path):
    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _pane(pilot, app)
            pane.query_one("#out").value = str(tmp_path)
            pane.focus()
            await pilot.press("a")
            await wait_for(pilot, lambda: "nothing to abort" in _status(pane), 30, "a said")
            # the age field: typed, then Escape back to the screen's keys, text kept
            pane.query_one("#simulate").value = False  # a person's run takes the age
            age = pane.query_one("#age", Input)
            age.focus()
            await wait_for(pilot, lambda: app.focused is age, 30, "age focused")
            await pilot.press("a", "b", "c")
            said = "age = 'abc': give whole years from 1 to 120"
            await wait_for(pilot, lambda: said in _status(pane), 30, "age refused")
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.focused is pane.focus_target, 30, "out of the field")
            assert age.value == "abc"
            await pilot.press("s")  # refused on the key: nothing starts
            await pilot.pause(0.3)
            assert pane.running is None and said in _status(pane)
            age.value = "31"
            await wait_for(pilot, lambda: "age =" not in _status(pane), 30, "line gone")

    asyncio.run(scenario())


def test_a_simulated_run_ignores_the_person_fields(double_plugins, map_file, tmp_path):
    """A simulated participant needs no age (the help says so): a bad age left in its
    field neither refuses the start nor is said while typed."""

    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            pane.query_one("#protocol").value = "exp1"
            pane.query_one("#out").value = str(tmp_path)
            assert pane.query_one("#simulate").value  # ticked
            pane.query_one("#age", Input).value = "Q"
            await pilot.pause(0.2)
            assert "age =" not in _status(pane), _status(pane)
            pane.focus()
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.running is not None, 30, "started")
            assert "age =" not in _status(pane), _status(pane)
            pane.control.abort("test over")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")

    asyncio.run(scenario())


def test_a_refused_start_is_not_said_stopped(double_plugins, tmp_path):
    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
            pane = await _pane(pilot, app)
            pane.query_one("#protocol").value = "exp2"
            pane.query_one("#out").value = str(tmp_path)
            pane.query_one("#simulate").value = False  # a person, with no details given
            pane.focus()
            await pilot.press("s")
            await wait_for(pilot, lambda: "missing" in _status(pane), 60, "refused")
            assert "refused: participant P01:" in _status(pane)
            assert "stopped:" not in _status(pane)

    asyncio.run(scenario())


def test_p_says_pausing_until_the_run_is_paused(double_plugins, map_file, tmp_path):
    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await _running(pilot, app, map_file, tmp_path)
            await pilot.press("p")
            text = _status(pane)
            if "paused (p resumes)" not in text:  # the trial in flight still plays
                assert "pausing after this trial" in text.splitlines()[0], text
            await wait_for(pilot, lambda: "paused (p resumes)" in _status(pane), 60, "paused")
            head = _status(pane).splitlines()[0]
            assert head.endswith("paused") and "pausing" not in _status(pane)
            await pilot.press("p")  # resume, then abort: nothing left running
            await pilot.press("a", "a")
            await wait_for(pilot, lambda: pane.running is None, 60, "aborted")

    asyncio.run(scenario())
