"""F-keys typed in one write land on the last one's screen (issue 27, fifth new-user try:
`F10 F1` in one `tmux send-keys` stayed on Studies). A focus given late to the screen
switched from (its widget kept from the last visit) took the console back there. Every
screen followed by F1, then every pair of screens, each typed as one burst once every
screen has been visited; the screen shown stays, its widget has the focus. 80 x 24 and
120 x 40."""

from __future__ import annotations

import asyncio

import pytest
from textual import events

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import app_processed, wait_for


async def _burst(app, pilot, keys: list[str], tab: str) -> None:
    """``keys`` posted at once (one write), then ``tab`` shown with the focus in it and
    still so after the keys' late effects (the focus given behind them)."""
    for key in keys:
        app.post_message(events.Key(key, None))

    def landed() -> bool:
        pane, focused = app.pane(tab), app.base.focused
        return (
            app.active_tab == tab
            and focused is not None
            and pane is not None
            and pane in focused.ancestors_with_self
        )

    await wait_for(pilot, landed, 30, f"{keys} -> {tab}")
    for _ in range(3):  # a deferred focus or tab switch behind them would show by now
        await app_processed(app)
        await pilot.pause(0.05)
    assert landed(), (keys, tab, app.active_tab, app.base.focused)


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_burst_of_f_keys_lands_on_the_last_ones_screen(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            keys = {tab: key for tab, (_title, key, _reg) in app.tabs.items() if key}
            for tab, key in keys.items():  # every screen built, its widget kept
                await _burst(app, pilot, [key], tab)
            first = next(iter(keys))
            for tab, key in keys.items():
                if tab != first:
                    await _burst(app, pilot, [key, keys[first]], first)
            for tab, key in keys.items():
                for other, other_key in keys.items():
                    if other != tab:
                        await _burst(app, pilot, [key, other_key], other)
            await _burst(app, pilot, [keys["studies"], keys["camera"], keys["signals"]], "signals")

    asyncio.run(scenario())
