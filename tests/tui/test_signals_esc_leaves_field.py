"""A new operator's try (Signals, F8, 80 x 24): Esc did nothing in the expression field
(type, Esc, ``q`` read ``...)q``) and nothing on screen said how to leave it. Esc leaves
any of the screen's fields for its library, what was typed kept, and the hint beside
the fields says so."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_screens import _ready


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
@pytest.mark.parametrize("field", ["#sig-expr", "#sig-name", "#sig-target"])
def test_esc_leaves_a_signals_field_keeping_its_text(plugins, size, field):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            box = app.query_one(field, Input)
            box.focus()
            await wait_for(pilot, lambda: box.has_focus, 10, "field focused")
            box.value, box.cursor_position = "sine(250 Hz, 20 V, 1 s)", 23
            await pilot.press("escape")
            await pilot.pause(0.2)
            assert not isinstance(app.focused, Input), app.focused
            assert app.focused is app.query_one("#sig-library"), app.focused
            assert box.value == "sine(250 Hz, 20 V, 1 s)"
            assert "esc leave" in words_on(app, "#sig-hint"), words_on(app, "#sig-hint")
            assert app.query_one("#sig-hint").content_region.width >= len(
                str(app.query_one("#sig-hint").render()).rstrip()
            ), "the hint is cut"

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_tab_from_the_library_goes_back_to_the_field_esc_left(plugins, size):
    """README and ``?``: Esc leaves a field for the library, "Tab goes back" (it went to
    the tab bar)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            box = app.query_one("#sig-name", Input)
            box.focus()
            await wait_for(pilot, lambda: box.has_focus, 10, "field focused")
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.focused is app.query_one("#sig-library"), 5, "lib")
            await pilot.press("tab")
            await pilot.pause(0.2)
            assert app.focused is box, app.focused
            library = app.query_one("#sig-library")
            library.focus()  # not from a field: Tab moves on as it always does
            await wait_for(pilot, lambda: library.has_focus, 5, "the library")
            await pilot.press("tab")
            await pilot.pause(0.2)
            assert app.focused is not library and app.focused is not box, app.focused

    asyncio.run(scenario())
