"""The Vibration screen after a map came in: Tab only reaches widgets that show their focus
(the command line, the grid, the tabs) and the grid still plays on enter; an e-stop during
an audition leaves a status line that says the e-stop stopped it, also after the reset."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import DataTable, Input
from textual.widgets._tabbed_content import ContentTabs

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import command, wait_for


def _status(app) -> str:
    return str(app.query_one("#vib-status").render())


def test_tab_never_focuses_an_invisible_widget(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="grid focused")
            await pilot.press("m")
            await wait_for(pilot, lambda: pane.session is not None, 120, "measured")
            await wait_for(pilot, lambda: "measured at" in _status(app), 30, "status")
            seen = []
            for _ in range(6):
                await pilot.press("tab")
                seen.append(app.focused)
            assert pane not in seen
            assert all(isinstance(w, (Input, DataTable, ContentTabs)) for w in seen), seen
            assert {Input if isinstance(w, Input) else type(w) for w in seen} >= {
                Input,
                ContentTabs,
            }
            # back on the grid, enter auditions the point under the cursor
            for _ in range(3):
                if app.focused is pane.focus_target:
                    break
                await pilot.press("tab")
            assert app.focused is pane.focus_target
            pane.move_cursor(51)
            await pilot.press("enter")
            await wait_for(pilot, lambda: len(app.session.played) == 1, what="point played")
            assert app.session.played[0].name == "point 51"

    asyncio.run(scenario())


@pytest.fixture
def long_pulse(tmp_path, plugins):
    """The sim profile with 3 s point pulses: "playing" (said once the outputs report the
    start) stays on the line long enough to be seen and e-stopped on a loaded machine."""
    from console.config.profile import PROJECT_PROFILES

    path = tmp_path / "longpulse.toml"
    path.write_text(
        (PROJECT_PROFILES / "sim.toml").read_text() + "\n[vibrotactile]\npulse_s = 3.0\n"
    )
    return Context(str(path), plugins)


def test_estop_during_an_audition_says_so_in_the_status(long_pulse, map_file):
    async def scenario():
        app = HapTableApp(long_pulse, fast=False, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            await command(app, pilot, f"load {map_file}")
            await wait_for(pilot, lambda: pane.session is not None, 30, "map loaded")
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="grid focused")
            pane.move_cursor(14)
            await pilot.press("enter")
            await wait_for(pilot, lambda: "playing point 14" in _status(app), 30, "playing")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stopped")
            await wait_for(
                pilot, lambda: "stopped by the e-stop" in _status(app), what="status after e-stop"
            )
            assert "point 14" in _status(app) and "playing" not in _status(app)
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            await pilot.pause(0.5)
            assert "point 14 stopped by the e-stop" in _status(app)
            # the next audition plays and then says it played
            await pilot.press("enter")
            await wait_for(pilot, lambda: "played point 14" in _status(app), 30, "played")

    asyncio.run(scenario())


def test_an_error_typed_while_a_point_plays_keeps_the_status_line(long_pulse, map_file):
    """The play's end does not write over a newer message: a bad command typed during an
    audition stays on the line after the audition ends."""

    async def scenario():
        app = HapTableApp(long_pulse, fast=False, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            await command(app, pilot, f"load {map_file}")
            await wait_for(pilot, lambda: pane.session is not None, 30, "map loaded")
            await command(app, pilot, "14")
            await wait_for(pilot, lambda: "playing point 14" in _status(app), 30, "playing")
            await command(app, pilot, "import PA")
            await wait_for(pilot, lambda: "EXC=FILE" in _status(app), 30, "import error")
            await wait_for(pilot, lambda: pane._now_playing is None, 30, "audition ended")
            await pilot.pause(0.2)
            assert "EXC=FILE" in _status(app)

    asyncio.run(scenario())
