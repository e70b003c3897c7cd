"""A hidden screen's echo of the e-stop goes to the log only, whenever it comes (issue
27: on Studies, ctrl+e and ctrl+r typed together left ``Devices: e-stop active ...;
ctrl+r resets`` on the title row under an idle safety bar: Devices' echo of the e-stop
came after the reset's notification and was raised over it)."""

from __future__ import annotations

import asyncio
import logging

import pytest

from console.cli.main import Context
from console.session.events import Stopped
from console.tui.app import HapTableApp
from console.tui.session_messages import SessionMessage

from .conftest import spy_notifications, wait_for
from .test_screens import _ready
from .test_stale_lines import estop_refused_reset


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_an_estop_echo_after_the_reset_never_shows(plugins, size, caplog):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        said = spy_notifications(app)
        async with app.run_test(size=size, notifications=True) as pilot:
            await _ready(app, pilot)
            await pilot.press("f1")  # Devices built, then hidden behind Studies
            await wait_for(pilot, lambda: app.pane("devices") is not None, 20, "Devices")
            devices = app.pane("devices")
            await pilot.press("f10")
            await pilot.pause(0.3)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 20, "e-stopped")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 20, "reset")
            await pilot.pause(0.5)
            n = len(said)
            with caplog.at_level(logging.INFO, "haptable.console"):
                # the e-stop's echo, late: Devices (hidden) hears the e-stop after the reset
                devices.on_session_message(
                    SessionMessage(Stopped("estop", reason="operator e-stop (console)"))
                )
                devices._show_result(
                    "e-stop active: operator e-stop (console); ctrl+r resets", True
                )
                await pilot.pause(0.3)
            late = said[n:]
            assert not any("e-stop" in s for s in late), late
            assert said[-1].startswith("e-stop reset"), said
            assert any("e-stop active" in r.getMessage() for r in caplog.records)  # logged

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24)], ids=["80x24"])
def test_a_late_estop_message_leaves_devices_saying_the_reset(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            devices = await estop_refused_reset(app, pilot)
            devices.on_session_message(
                SessionMessage(Stopped("estop", reason="operator e-stop (console)"))
            )
            await pilot.pause(0.2)
            assert "e-stop active" not in devices.result, devices.result

    asyncio.run(scenario())
