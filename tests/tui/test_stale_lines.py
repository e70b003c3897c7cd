"""A line that was true for a while leaves its screen when that while ends (issue 27):
Devices' ``... has ended: plays work again`` under a shell's e-stop, its ``e-stop
reset: t plays ...`` 15 minutes after the reset, and Vibration's refused ``: import
PA=/tmp/none.uff`` kept on its command line after Esc for the rest of the session."""

from __future__ import annotations

import asyncio

import pytest

import console.tui.panes.devices as devices_mod
from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.command_line import CommandLine
from console.tui.lapse import HELD_ENDED

from .conftest import command, wait_for
from .test_screens import _ready

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


async def estop_refused_reset(app, pilot):
    """Devices after ctrl+e, ``t`` refused during the e-stop and ctrl+r: its line says
    the reset. The pane."""
    await _ready(app, pilot)
    devices = app.pane("devices")
    await pilot.press("ctrl+e")
    await wait_for(pilot, lambda: app.session.outputs.estopped, 20, "e-stopped")
    await pilot.press("t")
    await wait_for(pilot, lambda: "refused" in devices.result, 20, "t refused")
    await pilot.press("ctrl+r")
    await wait_for(pilot, lambda: devices.result.startswith("e-stop reset"), 20, "reset")
    return devices


@SIZES
def test_plays_work_again_goes_with_an_estop(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            devices = app.pane("devices")
            devices._show_result(HELD_ENDED)  # a shell's long play ended
            app.session.outputs.estop("haptable estop (shell)")  # as `haptable estop`
            await wait_for(pilot, lambda: "e-stop" in devices.result, 10, devices.result)
            assert "plays work again" not in devices.result

    asyncio.run(scenario())


@SIZES
def test_the_reset_s_line_goes_after_a_while(plugins, size, monkeypatch):
    monkeypatch.setattr(devices_mod, "RESET_NEWS_S", 1.0)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            devices = await estop_refused_reset(app, pilot)
            await wait_for(pilot, lambda: "e-stop reset" not in devices.result, 5, "gone")

    asyncio.run(scenario())


@SIZES
def test_esc_clears_a_refused_command(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            await command(app, pilot, "import PA=/tmp/none.uff")
            line = app.query_one("#vib-cmd", CommandLine)
            await wait_for(pilot, lambda: app.focused is line, 20, "the refused command kept")
            assert line.value == "import PA=/tmp/none.uff"
            await pilot.press("escape")
            await pilot.pause(0.2)
            assert app.focused is not line
            assert line.value == "", line.value

    asyncio.run(scenario())
