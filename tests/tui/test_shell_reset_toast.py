"""`haptable estop` then `haptable reset` typed at another terminal while the console
shows: the console says each once (a new user saw the reset toast twice)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from ..kernel.test_kernel import at_terminal, haptable
from .conftest import spy_notifications, wait_for
from .test_screens import _ready


def _said(said: list[str], start: str) -> list[str]:
    return [m for m in said if m.startswith(start)]


def test_a_shell_estop_and_reset_are_each_said_once(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="devices")
        said = spy_notifications(app)  # the title row shows the newest only
        async with app.run_test(size=(120, 40), notifications=True) as pilot:
            await _ready(app, pilot)
            await asyncio.to_thread(haptable, "--profile", "sim", "estop")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 20, "e-stopped")
            code, text = await asyncio.to_thread(at_terminal, "--profile", "sim", "reset")
            assert code == 0, text
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 20, "reset")
            await pilot.pause(1.0)  # a second toast would come with the next reads
            assert len(_said(said, "E-STOP")) == 1, said
            assert len(_said(said, "e-stop reset")) == 1, said

    asyncio.run(scenario())
