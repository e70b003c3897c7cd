"""A screen's ``:`` command line keeps what the operator typed when the command fails
(issue 27): the text stays, the cursor at its end, ``:`` comes back to it; a command that
succeeded is cleared. A text field's keys act in the order typed: ``ctrl+u`` followed at
once by text (one write, as ``tmux send-keys C-u 'host:3333' Enter`` sends it) keeps the
text."""

from __future__ import annotations

import asyncio

from textual import events
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.command_line import CommandLine

from .conftest import command, wait_for
from .test_screens import _ready


def _status(app) -> str:
    return str(app.query_one("#vib-status").render())


def test_a_failed_command_keeps_its_text_and_a_successful_one_clears_it(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            line = app.query_one("#vib-cmd", CommandLine)
            # an import of a file that does not exist fails in its worker: the line
            # keeps the command
            bad = "import PA=/nonexistent/pa.uff"
            await command(app, pilot, bad)
            await wait_for(pilot, lambda: "pa.uff" in _status(app), 20, "the import's error")
            await pilot.pause(0.2)
            assert line.value == bad
            # the keys are the line's again (the letters typed next fix it, they never
            # act as the grid's keys), the cursor at its end
            await wait_for(pilot, lambda: app.focused is line, 10, "the line")
            assert line.cursor_position == len(bad) and line.selection.is_empty
            await pilot.press("x")  # a key adds to the line, never replaces it
            assert line.value == bad + "x"
            await pilot.press("escape")
            # a command refused at once keeps its text too
            await command(app, pilot, "hand 51 sideways")
            await wait_for(pilot, lambda: "hand POINT" in _status(app), 10, "refused")
            assert line.value == "hand 51 sideways"
            # ":" typed on the kept command starts a new one instead of gluing onto it
            await wait_for(pilot, lambda: app.focused is line, 10, "the line")
            await pilot.press("colon", "5", "1")
            await wait_for(pilot, lambda: line.value == "51", 10, "a new command")
            line.value = "hand 51 sideways"
            # a load that works clears the line (once its work has ended)
            await command(app, pilot, f"load {map_file}")
            await wait_for(pilot, lambda: pane.session is not None, 30, "map loaded")
            await wait_for(pilot, lambda: line.value == "", 10, "the line cleared")
            # and an audition, accepted at once, too
            await command(app, pilot, "51")
            await wait_for(pilot, lambda: line.value == "", 10, "cleared")
            await command(app, pilot, "999")
            await wait_for(pilot, lambda: "point 999" in _status(app), 10, "refused")
            assert line.value == "999"

    asyncio.run(scenario())


def test_a_command_typed_in_one_write_with_its_colon_reaches_the_line(plugins):
    """``:`` and the command in one write (``tmux send-keys : '99' Enter``): the keys
    after ``:`` go to the line, not to the grid (Enter there would audition a point)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            line = app.query_one("#vib-cmd", CommandLine)
            for key in ["colon", "h", "a", "n", "d", "enter"]:
                char = {"colon": ":", "enter": "\r"}.get(key, key)
                app._driver.send_message(events.Key(key, char))
            await wait_for(pilot, lambda: "hand" in _status(app), 10, "the command's answer")
            assert "hand POINT" in _status(app)  # "hand" alone: refused, not a key
            assert line.value == "hand"

    asyncio.run(scenario())


def test_ctrl_u_then_text_in_one_write_keeps_the_text(plugins):
    """The keys of one terminal write reach the app before the field handles any: the
    field's own keys (ctrl+u, backspace, home, enter) must still act in order."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            field = app.query_one("#sig-name", Input)
            field.focus()
            await wait_for(pilot, lambda: app.focused is field, 10, "the name field")
            field.value = "old"
            field.cursor_position = 3
            await pilot.pause(0.1)
            # one write: the driver posts every key before the app handles the first
            keys = ["ctrl+u", *"host:3333", "backspace", "4", "home", "ctrl+k", *"abc", "end"]
            for key in keys:
                bound = key in ("ctrl+u", "backspace", "home", "ctrl+k", "end")
                app._driver.send_message(
                    events.Key({":": "colon"}.get(key, key), None if bound else key)
                )
            seen: list[str] = []
            app.watch(field, "value", lambda v: seen.append(v), init=False)
            await wait_for(pilot, lambda: field.value == "abc", 10, f"abc typed last ({seen})")
            assert "host:3334" in seen, seen  # what the keys before home typed
            await pilot.pause(0.3)
            assert field.value == "abc"

    asyncio.run(scenario())
