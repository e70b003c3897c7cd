"""The quit question fits the title row with its fix in view (issue 27: at 80 x 24 it
read ``q again within 3 s to quit: it loses your unsaved signal…``, ctrl+s only in the
log; with a demo running even less fitted). The log has it whole."""

from __future__ import annotations

import asyncio

import pytest
from textual.content import Content
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_signals_panel import _type


@pytest.mark.parametrize("demo", [False, True], ids=["alone", "demo"])
@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_quit_question_shows_its_fix(plugins, size, demo):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            expr = app.query_one("#sig-expr", Input)
            await wait_for(pilot, lambda: app.focused is expr, 10, "expression focused")
            expr.value = ""
            await _type(pilot, "sine(250 Hz, 20 V, 0.5 s)")
            if demo:
                app.work_under_way = lambda: ["the flow demo", "demo flow"]
            await pilot.press("escape", "q")
            await pilot.pause(0.5)
            notes = list(app._notifications)
            assert notes, "no question"
            shown = Content.from_markup(app._fitted(notes[-1]).message).plain  # the toast
            assert "…" not in shown, shown
            assert "q again within 3 s" in shown, shown
            assert "ctrl+s on Signals saves it" in shown, shown
            assert len(shown) <= size[0] - 3, shown
            if demo and size[0] >= 120:
                assert "the flow demo" in shown, shown
            await pilot.press("q")
            await wait_for(pilot, lambda: not app.is_running, 10, "quit on the second q")

    asyncio.run(scenario())
