"""The tests' pilot: a key that quits the console ends its press, even when the console
exits with an animation under way (Textual's press then waited for the animations for
good: a CI run hung on ctrl+q in test_signals_quit_unsaved after the console had quit)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def test_a_key_that_quits_the_console_ends_its_press(plugins, monkeypatch):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.focused is not None, what="focus")
            never = asyncio.Event()

            async def animations_never_complete() -> None:
                await never.wait()

            monkeypatch.setattr(app._animator, "wait_until_complete", animations_never_complete)
            await asyncio.wait_for(pilot.press("ctrl+q"), 60)
            assert not app.is_running

    asyncio.run(scenario())
