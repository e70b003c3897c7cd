"""Relays: the arrows move between the switches, so Down then Enter toggles the next
relay (Down scrolled the screen and Enter toggled relay 1)."""

from __future__ import annotations

import asyncio

import pytest
from textual import events

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_down_then_enter_toggles_relay_2(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            pane = app.pane("relays")
            await wait_for(pilot, lambda: app.focused is pane.focus_target, 10, "relay 1")
            # as a terminal delivers them: the Enter right behind the arrow, both queued
            # before either is handled
            app.post_message(events.Key("down", None))
            app.post_message(events.Key("enter", "\r"))
            await pilot.pause(0.3)
            assert app.focused.id == "relay-2"
            out = app.session.outputs
            await wait_for(pilot, lambda: 2 in out.operator_relays(), 10, "relay 2 closed")
            assert 1 not in out.operator_relays()
            await pilot.press("up", "up")
            await pilot.pause(0.2)
            assert app.focused.id == "relay-1"

    asyncio.run(scenario())
