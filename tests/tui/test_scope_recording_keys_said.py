"""Scope (F9): a recording's own keys (`e` its gate events, `[`/`]` its plans) pressed on
the live view say why they do nothing there and what to do (`o` opens a recording),
instead of nothing at all (a new operator's try: `e` was silent); the next key of the
live view takes the words away."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_recording_keys_on_the_live_view_say_what_to_do(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scope")
        async with app.run_test(size=size) as pilot:
            head = lambda: words_on(app, "#scope-head")  # noqa: E731
            await wait_for(pilot, lambda: head().startswith("LIVE"), 20, "the live view")
            await pilot.press("e")
            await wait_for(pilot, lambda: "o opens" in head(), 10, "e answered")
            assert "gate events" in head() and "recording" in head(), head()
            assert head().startswith("LIVE"), head()  # still the live view
            await pilot.press("space")  # the live view's own key: the words go
            await wait_for(pilot, lambda: "o opens" not in head(), 10, "the words gone")
            await pilot.press("space")
            await pilot.press("right_square_bracket")
            await wait_for(pilot, lambda: "o opens" in head(), 10, "] answered")
            assert "plans" in head(), head()

    asyncio.run(scenario())
