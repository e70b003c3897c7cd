"""Signals (F8): a wrong unit typed is named as a unit, with its column and what the
value takes, on the status line in one line (a new operator's try: ``sine(250 hz, 40 v,
0.5 sec)`` and ``sine(250 kV, ...)`` were told a comma was missing at column 6)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input, Static

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for

KEYS = {" ": "space", "(": "left_parenthesis", ")": "right_parenthesis", ",": "comma",
        ".": "full_stop"}  # fmt: skip


def _status(app) -> str:
    return " ".join(str(app.query_one("#sig-status", Static).render()).split())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_wrong_unit_is_named_where_it_was_typed(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is expr, 10, "expression focused")
            for typed, says in (
                ("sine(250 hz, 40 v, 0.5 sec)", "unit 'hz' at column 10 (250 hz): write Hz; "
                 "sine's frequency takes Hz or kHz"),
                ("sine(250 kV, 40 V, 0.5 s)", "unit 'kV' at column 10 (250 kV): not a unit "
                 "of the signal language; sine's frequency takes Hz or kHz"),
            ):  # fmt: skip
                await pilot.press("ctrl+u")
                await pilot.press(*[KEYS.get(c, c) for c in typed])
                assert expr.value == typed
                await pilot.press("enter")
                await wait_for(pilot, lambda s=says: s in _status(app), 10, "the unit named")
                assert "comma" not in _status(app)

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_character_outside_the_language_is_named_where_it_was_typed(plugins, size):
    """Issue 27, fifth new-user try: ``sine([250] Hz, 40 V, 0.5 s)`` was told a comma was
    missing at column 6 (``console.signals.syntax.check_text``: one rule for them all)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is expr, 10, "expression focused")
            expr.value = "sine([250] Hz, 40 V, 0.5 s)"
            await pilot.press("enter")
            says = "'[' at column 6 is not part of the signal syntax"
            await wait_for(pilot, lambda: says in _status(app), 10, "the bracket named")
            assert "not [250] Hz" in _status(app), _status(app)  # the fix, whole
            assert "comma" not in _status(app)

    asyncio.run(scenario())
