"""An e-stop from elsewhere (a shell's `haptable estop`, a demo's watchdog) is a toast and
in the log, as the README says; the console's own ctrl+e and ctrl+r are said once, not
twice (seventh new-user try: only the safety bar changed)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import spy_notifications, wait_for
from .test_screens import _ready


def test_an_estop_from_elsewhere_is_a_toast_and_ours_is_said_once(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        said = spy_notifications(app)
        async with app.run_test(size=(80, 24), notifications=True) as pilot:
            await _ready(app, pilot)
            app.session.outputs.estop("haptable estop (pid 4242) from a shell")
            await wait_for(
                pilot,
                lambda: any("E-STOP: " in m and "pid 4242" in m for m in said),
                what="the shell's e-stop said",
            )
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            await pilot.pause(0.5)
            assert sum("e-stop reset" in m for m in said) == 1, said
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stopped")
            await pilot.pause(0.5)
            assert sum(m.startswith("E-STOP") for m in said) == 2, said

    asyncio.run(scenario())
