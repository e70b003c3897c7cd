"""Devices (F1) at 80 x 24: a line saying the e-stop was reset is replaced when the
e-stop latches again (`haptable estop` from a shell): the screen never says "reset"
under an E-STOP safety bar."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.kernel.line_server import request
from console.tui.app import HapTableApp

from .conftest import wait_for


def test_a_new_estop_replaces_the_reset_line(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            pane = app.pane("devices")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 30, "e-stopped")
            await pilot.press("t")
            await wait_for(pilot, lambda: "refused" in pane.result, 30, "refused")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: pane.result.startswith("e-stop reset"), 30, "reset")
            # as `haptable estop` does it: the table's control socket
            sock = app.session.outputs.table.control_sock
            await asyncio.to_thread(request, sock, "estop haptable estop (a shell)", timeout_s=5)
            await wait_for(pilot, lambda: app.session.outputs.estopped, 30, "latched again")
            await wait_for(pilot, lambda: not pane.result.startswith("e-stop reset"), 10, "")
            assert "e-stop active" in pane.result and "ctrl+r resets" in pane.result
            assert "haptable estop" in pane.result, pane.result

    asyncio.run(scenario())
