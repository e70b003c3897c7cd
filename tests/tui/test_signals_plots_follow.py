"""Signals (F8): the waveform's title names the target it shows, never one it does not
(``waveform on PA`` stayed over "no signal" after ``PZ`` was refused, and while ``PA,PC``
was typed but not plotted), and a successful save plots the saved signal (the plots said
"no signal: enter plots it" after an error, even once the signal was saved)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.signals.design import parse_target
from console.tui.app import HapTableApp
from console.tui.panes.signals import wave_title

from .conftest import wait_for


def test_wave_title():
    assert wave_title(None, "PA") == "waveform"
    assert wave_title(parse_target("PA,PC"), "pc+pa") == "waveform on PA,PC"
    assert wave_title(parse_target("PA"), "PA,PC") == "waveform on PA (enter: PA,PC)"
    assert wave_title(parse_target("PA"), "PZ") == "waveform on PA (enter: PZ)"
    assert wave_title(parse_target("screen"), "screen") == "waveform on screen"


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_plots_say_what_they_show(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            pane = app.query_one("#sig-expr").parent
            wave = app.query_one("#sig-wave")
            await wait_for(pilot, lambda: wave.title == "waveform on PA", 20, "first plot")
            target = app.query_one("#sig-target", Input)
            target.value = "PA,PC"
            await pilot.pause(0.1)
            assert wave.title == "waveform on PA (enter: PA,PC)", wave.title
            target.focus()
            await pilot.press("enter")
            await wait_for(pilot, lambda: wave.title == "waveform on PA,PC", 20, "replot")
            target.value = "PZ"
            await pilot.press("enter")
            await wait_for(pilot, lambda: pane.preview is None, 20, "refused")
            await pilot.pause(0.1)
            assert "on PA" not in wave.title and "no signal" in wave.empty_text, wave.title
            target.value = "PB"
            expr = app.query_one("#sig-expr", Input)
            good, expr.value = expr.value, "sine(250 Hz"  # an error in the expression
            expr.focus()
            await pilot.press("enter")
            await wait_for(pilot, lambda: pane.preview is None, 20, "refused")
            assert "waveform on" not in wave.title, wave.title
            expr.value = good  # mended, then saved: the plots show it again
            app.query_one("#sig-name", Input).value = "mine"
            await pilot.press("ctrl+s")
            await wait_for(pilot, lambda: pane.preview is not None, 20, "plotted on save")
            assert wave.title == "waveform on PB" and wave.series, wave.title
            status = str(app.query_one("#sig-status").render())
            assert "saved mine" in status, status

    asyncio.run(scenario())
