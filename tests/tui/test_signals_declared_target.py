"""Signals (F8): a library signal keeps the channel it is meant for. Enter on the built-in
``screen-180`` (100 Vpp on the screen) puts ``screen`` in the target field, and ctrl+o
plays it there; a signal saved with a target loads with it; a target changed after the
load is an edit the play's line says (not the library signal's name)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input, OptionList

from console.cli.main import Context
from console.config.signal_library import BUILTIN, add_signal, library_path, read_library
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_signals_truthful_lines import _pane


async def _load(app, pilot, name: str) -> None:
    pane = app.pane("signals")
    library = app.query_one("#sig-library", OptionList)
    library.focus()
    library.highlighted = list(pane.entries).index(name)
    await pilot.press("enter")
    await pilot.pause(0.2)
    if app.query_one("#sig-name", Input).value != name:  # it asked: over typed work
        await pilot.press("enter")
    await wait_for(pilot, lambda: app.query_one("#sig-name", Input).value == name, 5, name)


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_library_signal_plays_on_the_channel_it_is_meant_for(plugins, size):
    assert BUILTIN["screen-180"].target == "screen"
    add_signal(
        library_path("sim"), "pc-pulse", "sine(200 Hz, 10 V, 0.2 s) * ramp(10 ms)", target="PC"
    )
    assert read_library(library_path("sim")).entries["pc-pulse"].target == "PC"

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            pane, lines = await _pane(app, pilot)
            target = app.query_one("#sig-target", Input)
            assert target.value == "PA"
            await _load(app, pilot, "screen-180")
            assert target.value == "screen"
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: any(x.startswith("played") for x in lines), 30, "")
            assert "played screen-180 on screen (1.00 s)" in lines, lines
            seg = app.session.played[-1].segments[0]  # the gate checked the screen's plan
            assert seg.screen and not seg.patches and not seg.piezo_v.any()
            # a saved signal with its own target
            await _load(app, pilot, "pc-pulse")
            assert target.value == "PC"
            # a signal with no declared target leaves the field as it is
            await _load(app, pilot, "tone-250")
            assert target.value == "PC"
            # changing the loaded signal's target is an edit: the line does not call the
            # play by the library signal's name
            await _load(app, pilot, "screen-180")
            target.value = "PA"
            lines.clear()
            await pilot.press("ctrl+o")
            await wait_for(
                pilot,
                lambda: any(x.startswith(("played", "designed")) or "refused" in x for x in lines),
                30,
                "",
            )
            assert not any(x.startswith("played screen-180 on PA") for x in lines), lines
            assert "played designed (screen-180 edited) on PA (1.00 s)" in lines, lines

    asyncio.run(scenario())
