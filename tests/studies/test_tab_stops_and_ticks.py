"""A second new operator's try on Studies: from Start, Tab reached a stop the footer named
no key for (the trials table), and a name typed where the participant field was thought
to be had its space untick `[x] simulated`. Every Tab stop now has its own word first in
the footer, and a space that follows characters typed at a check box is a word's space:
the box stays as it was and the status says where the focus is."""

from __future__ import annotations

import asyncio

import pytest

from .studies_pilot import studies_app, studies_pane, wait_for


def _footer(app) -> str:
    return [s.text for s in app.screen._compositor.render_strips()][-1]


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_every_tab_stop_is_named_and_a_typed_space_leaves_a_tick(double_plugins, size, monkeypatch):
    from textual.widgets import Input, Tabs

    from console.tui import ticks  # lazy: the console loads with the pilot
    from console.tui.focus_keys import own_key, shown_words  # lazy: as above

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app)
            start = pane.focus_target
            await wait_for(pilot, lambda: app.focused is start, 20, "Start")
            unnamed = []
            for _ in range(40):
                await pilot.press("tab")
                w = app.focused
                if w is start:
                    break
                if isinstance(w, Input | Tabs):  # a cursor in it; the tab bar's ←→ screens
                    continue
                if not (own_key(w) or shown_words(w)):
                    unnamed.append(type(w).__name__ + f"#{w.id}")
            assert not unnamed, unnamed  # each stop names itself first in the footer
            simulate = pane.query_one("#simulate")
            simulate.focus()
            await wait_for(pilot, lambda: app.focused is simulate, 10, "simulated")
            assert simulate.value
            await pilot.press("j", "u", "l", "e", "space")  # a name typed at the box
            status = pane.query_one("#study-status")
            await wait_for(pilot, lambda: "space not taken" in str(status.render()), 10, "said")
            assert simulate.value, "a word's space unticked the box"
            assert "'simulated' check box" in str(status.render())
            await pilot.pause(ticks.TYPING_S + 0.1)
            await pilot.press("space")  # a space alone ticks as always
            await wait_for(pilot, lambda: not simulate.value, 10, "unticked")

    monkeypatch.setattr("console.tui.ticks.TYPING_S", 0.3)
    asyncio.run(scenario())
