"""A new operator's try, finding 11 (80 x 24): wherever Tab lands the footer names what
Enter or Space does there. On Studies the buttons and check boxes each show their own key
(``⏎ start``, ``space record trials``) and the arrow buttons, which the arrow keys
duplicate, are no Tab stops; on Devices every Tab stop shows a key of its own (no stop
that only scrolls), the sound-card list has the focus as the screen first shows (README)
and coming back to F1 the list the operator left has it again."""

from __future__ import annotations

import asyncio
import re

from textual.widgets import Button, Checkbox, DataTable, Select, Tabs

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def _footer(app) -> str:
    return app.screen._compositor.render_strips()[-1].text


async def _tab_stops(app, pilot, count: int) -> list[tuple[object, str]]:
    """(focused widget, footer) at each of ``count`` Tab presses, the first before any."""
    seen = []
    for _ in range(count):
        focused = app.focused
        await wait_for(pilot, lambda: app.focused is not None, 10, "a focus")
        await pilot.pause(0.1)  # the footer rebuilds after a refresh
        seen.append((focused, _footer(app)))
        await pilot.press("tab")
    return seen


def test_studies_buttons_and_check_boxes_name_themselves_and_arrows_are_no_stops(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("studies") is not None, 30, "studies")
            pane = app.pane("studies")
            await wait_for(pilot, lambda: app.focused is pane.focus_target, 30, "Start")
            stops = await _tab_stops(app, pilot, 40)
            chain = [w for w, _ in stops]
            first_again = chain.index(chain[0], 1)  # round the whole chain once
            chain, stops = chain[:first_again], stops[:first_again]
            assert not [w for w in chain if "answer" in w.classes], "arrow buttons are stops"
            assert len(chain) <= 20, [type(w).__name__ for w in chain]
            for widget, footer in stops:
                if isinstance(widget, Button):
                    word = str(widget.label).lower()
                    # named first, or its screen key (s start) marked as the same: ⏎/s start
                    assert footer.startswith(f"⏎ {word} ") or re.search(
                        rf"(^| )⏎/\S+ {re.escape(word)} ", footer
                    ), (widget.id, footer)
                elif isinstance(widget, Checkbox):
                    word = str(widget.label)
                    assert footer.startswith(f"space {word} "), (widget.id, footer)
            names = [f for w, f in stops if isinstance(w, Button | Checkbox)]
            assert len(set(names)) == len(names), names  # no two alike

    asyncio.run(scenario())


def test_every_devices_tab_stop_shows_its_own_key_and_f1_comes_back_to_the_list_left(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("devices") is not None, 30, "devices")
            cards = app.query_one("#audio-table", DataTable)
            await wait_for(pilot, lambda: app.focused is cards, 30, "the sound cards")
            stops = await _tab_stops(app, pilot, 8)
            for widget, footer in stops:
                own = isinstance(widget, DataTable | Select | Tabs)
                assert own, f"a Tab stop on {type(widget).__name__} with no key of its own"
                # the drop-down named first (a field: ``name_field``), then its Enter
                want = ("test signal: ⏎ ",) if isinstance(widget, Select) else ("⏎ ", "←→ ")
                assert footer.startswith(want), (type(widget).__name__, footer)
            # the doctor's table focused when leaving: F1 again comes back to it
            doctor = app.query_one("#device-table", DataTable)
            doctor.focus()
            await wait_for(pilot, lambda: app.focused is doctor, 10, "the doctor's table")
            await pilot.pause(0.2)
            await pilot.press("f4")
            await wait_for(pilot, lambda: app.active_tab == "relays", 10, "relays")
            await pilot.press("f1")
            await wait_for(pilot, lambda: app.active_tab == "devices", 10, "devices")
            await pilot.pause(0.5)
            assert app.focused is doctor, app.focused

    asyncio.run(scenario())
