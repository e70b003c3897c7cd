"""Typed work is never lost to a key: q (or ctrl+q) with an unsaved signal expression on
the Signals screen asks first, says what would be lost and how to keep it, and quits on a
second q; a saved expression quits at once (found by a new operator at 80 x 24)."""

from __future__ import annotations

import asyncio

from textual.widgets import Input, OptionList

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_signals_panel import _type

TYPED = "sine(250 Hz, 20 V, 0.5 s) * ramp(5 ms)"


def test_q_with_an_unsaved_expression_asks_before_it_quits(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is expr, 10, "expression focused")
            expr.value = ""
            await _type(pilot, TYPED)
            lib = app.query_one("#sig-library", OptionList)
            for _ in range(6):  # Tab on to the library list, as the operator did
                if app.focused is lib:
                    break
                await pilot.press("tab")
            assert app.focused is lib
            await pilot.press("q")
            await pilot.pause(0.3)
            assert app.is_running, "one q lost the typed expression"
            shown = [str(n.message) for n in app._notifications]
            assert any(
                "q again within 3 s quits, losing your signal (ctrl+s on Signals saves it)" in m
                for m in shown
            ), shown
            assert expr.value == TYPED  # still there to save
            await pilot.press("q")
            await wait_for(pilot, lambda: not app.is_running, 10, "quit on the second q")

    asyncio.run(scenario())


def test_q_again_in_the_expression_field_quits_and_types_nothing(plugins):
    """ctrl+q with the focus in the edited expression, then q: the second key is the
    confirmation's (it used to be typed: ``... %q``, and the console stayed)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is expr, 10, "expression focused")
            expr.value = ""
            await _type(pilot, TYPED)
            await pilot.press("ctrl+q")
            await pilot.pause(0.3)
            assert app.is_running and app.focused is expr
            await pilot.press("q")
            assert expr.value == TYPED, expr.value  # the typed work is not changed by it
            await wait_for(pilot, lambda: not app.is_running, 10, "quit on the second q")

    asyncio.run(scenario())


def test_q_after_the_confirmation_ran_out_is_typed(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        app.QUIT_CONFIRM_S = 0.2
        async with app.run_test(size=(80, 24)) as pilot:
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is expr, 10, "expression focused")
            expr.value = ""
            await _type(pilot, TYPED)
            await pilot.press("ctrl+q")
            await pilot.pause(0.5)
            await pilot.press("q")
            await pilot.pause(0.2)
            assert app.is_running and expr.value == TYPED + "q"

    asyncio.run(scenario())


def test_a_saved_or_untouched_expression_quits_at_once(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.focused is not None, what="focus")
            assert app.unsaved_work() == []  # the default expression is nobody's work
            await pilot.press("ctrl+q")
            await wait_for(pilot, lambda: not app.is_running, 10, "quit")

    asyncio.run(scenario())
