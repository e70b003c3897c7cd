"""An e-stop from a shell (`haptable estop`) right after the console's ctrl+r: its E-STOP
toast replaces the reset's at once (a new operator's try, Relays at 80 x 24: the reset's
toast stayed ~3 s and no E-STOP toast came, the e-stop taken for the reset's own echo).
The console's own ctrl+e and ctrl+r are still said once each."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets._toast import Toast

from console.cli.main import Context
from console.tui.app import HapTableApp

from ..kernel.test_kernel import haptable
from .conftest import spy_notifications, wait_for
from .test_screens import _ready


def _toast_text(app) -> str:
    return " ".join(str(t.render()) for t in app.screen.query(Toast))


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_shell_estop_right_after_a_reset_replaces_its_toast(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="relays")
        said = spy_notifications(app)
        async with app.run_test(size=size, notifications=True) as pilot:
            await _ready(app, pilot)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 20, "e-stopped")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 20, "reset")
            await wait_for(pilot, lambda: "e-stop reset" in _toast_text(app), 10, "reset toast")
            done = await asyncio.to_thread(haptable, "--profile", "sim", "estop")
            assert done.returncode == 0, done.stderr
            await wait_for(pilot, lambda: app.session.outputs.estopped, 20, "e-stopped again")
            await wait_for(pilot, lambda: "E-STOP: haptable estop" in _toast_text(app), 3)
            assert "e-stop reset" not in _toast_text(app), _toast_text(app)
            await pilot.pause(0.5)
            # the console's own keys said once each, the shell's e-stop once
            assert sum(m.startswith("E-STOP: outputs silenced") for m in said) == 1, said
            assert sum(m.startswith("e-stop reset") for m in said) == 1, said
            assert sum(m.startswith("E-STOP: haptable estop") for m in said) == 1, said

    asyncio.run(scenario())
