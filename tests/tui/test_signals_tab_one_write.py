"""Issue 27, fourth new-user try: Signals, the expression then Tab and a name typed in one
write (a paste, ``tmux send-keys``): the Tab moves on before the name's keys, which land
in the name field; the Tab was dropped and the name went into the expression."""

from __future__ import annotations

import asyncio

from textual import events
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_screens import _ready

EXPR = "sine(250 Hz, 20 V, 1 s) * ramp(10 ms)"


def test_tab_then_a_name_in_one_write_fills_both_fields(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            expr = app.query_one("#sig-expr", Input)
            name = app.query_one("#sig-name", Input)
            expr.focus()
            await wait_for(pilot, lambda: app.focused is expr, 10, "the expression field")
            expr.value = ""
            await pilot.pause(0.1)
            # one write: the driver posts every key before the app handles the first
            for key in [*EXPR, "tab", *"abc", "shift+tab", "end", *"+x", "tab", "tab", *"PC"]:
                char = None if key in ("tab", "shift+tab", "end") else key
                named = {" ": "space", "(": "left_parenthesis", ")": "right_parenthesis"}
                named |= {",": "comma", "*": "asterisk", "+": "plus"}
                app._driver.send_message(events.Key(named.get(key, key), char))
            target = app.query_one("#sig-target", Input)
            await wait_for(pilot, lambda: target.value.endswith("PC"), 10, "PC typed last")
            await pilot.pause(0.3)
            assert name.value == "abc"
            assert expr.value == EXPR + "+x"
            assert app.focused is target

    asyncio.run(scenario())
