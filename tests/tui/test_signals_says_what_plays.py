"""Signals (F8): the line names the signal that plays. A signal typed into the name field
(Tab goes there from the expression) is no name: ctrl+o refuses it as ctrl+s does, and
never announces the name field's text while the expression field's signal plays. While
a demo holds the outputs, ctrl+o is refused at once, naming the demo and how to stop it
(the play waited 13 s for a silence the demo's stream never leaves)."""

from __future__ import annotations

import asyncio
import time

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_demos import _start
from .test_signals_truthful_lines import _pane as _pane_lines

PLAYS = "saw(100 Hz, 5 V, 2 s) * ramp(10 ms)"
TYPED_AS_NAME = "sine(100 Hz, 30 V, 5 s) * ramp(10 ms)"


def _status(app) -> str:
    return " ".join(str(app.query_one("#sig-status").render()).split())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_an_expression_in_the_name_field_is_refused_not_announced(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            _pane, lines = await _pane_lines(app, pilot)
            app.query_one("#sig-expr", Input).value = PLAYS
            app.query_one("#sig-name", Input).value = TYPED_AS_NAME
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: "signal name" in _status(app), 20, str(lines))
            await pilot.pause(0.5)
            assert not any("sine(" in x and "signal name" not in x for x in lines), lines
            assert not any(x.startswith(("playing", "starting", "checking")) for x in lines)
            assert "ctrl+o" in _status(app), _status(app)  # how to play after all
            assert not app.session.played

    asyncio.run(scenario())


def test_play_while_a_demo_runs_is_refused_at_once_naming_it(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await _start(app, pilot, "knob")
            await pilot.press("f8")
            pane = app.pane("signals")
            await wait_for(pilot, lambda: bool(pane.entries), 10, "library")
            app.query_one("#sig-expr", Input).value = PLAYS
            app.query_one("#sig-name", Input).value = ""
            t0 = time.monotonic()
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: "holds the outputs" in _status(app), 8, _status(app))
            assert time.monotonic() - t0 < 5
            line = _status(app)
            assert "knob demo" in line and "s on Scenes" in line, line
            await pilot.press("ctrl+e")

    asyncio.run(scenario())
