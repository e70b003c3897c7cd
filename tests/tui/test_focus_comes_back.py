"""A screen left with a half-typed line gets the focus back on that line, nothing
selected: what the operator types next continues it (the rest of `:hand 51 ri` became the
Vibration grid's keys, and on Signals one key replaced the selected expression)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_command_line_keeps_the_focus_across_screens(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            await pilot.press("colon")
            line = app.query_one("#vib-cmd", Input)
            await wait_for(pilot, lambda: app.focused is line, 10, "command line focused")
            await pilot.press(*"hand 51 ri")
            await pilot.press("f4")
            await wait_for(pilot, lambda: app.active_tab == "relays", 10, "relays")
            await pilot.press("f3")
            await wait_for(pilot, lambda: app.focused is line, 10, "focus back on the line")
            await pilot.press(*"ght")
            assert line.value == "hand 51 right"
            assert not app.session.played  # no key went to the grid

    asyncio.run(scenario())


def test_the_signal_expression_is_continued_not_replaced(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is not None, 10, "focus")
            expr.focus()
            await wait_for(pilot, lambda: app.focused is expr, 10, "expression focused")
            expr.value = "sine(250 Hz, 20 V, 0.5 s)"
            expr.cursor_position = len(expr.value)
            await pilot.press("f3")
            await wait_for(pilot, lambda: app.active_tab == "vibration", 10, "vibration")
            await pilot.press("f8")
            await wait_for(pilot, lambda: app.focused is expr, 10, "focus back")
            await pilot.press(*" * ramp(5 ms)")
            assert expr.value == "sine(250 Hz, 20 V, 0.5 s) * ramp(5 ms)"

    asyncio.run(scenario())
