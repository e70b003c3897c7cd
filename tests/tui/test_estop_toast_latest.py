"""The title row's notification about the e-stop says the latest state (a new user's
trial, tmux 80 x 24, twin profile):

- ctrl+e and ctrl+r within a few milliseconds (``tmux send-keys C-e C-r``): the title row
  kept ``E-STOP: operator e-stop (console)`` for 12 s under an ``idle`` safety bar, the
  e-stop's echo arriving after the reset was taken for news from elsewhere. Whatever the
  order and timing, the reset's notification replaces the e-stop's.
- ctrl+e on Relays (or Electrostatic, Scenes, Studies): Devices, hidden, saying the
  e-stop on its own status line took the title row (``Devices: e-stop active: ...``). A
  hidden screen's status goes to the log, never as a toast over the e-stop's.

80 x 24 and 120 x 40."""

from __future__ import annotations

import asyncio

import pytest
from textual import events
from textual.widgets._toast import Toast

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import spy_notifications, wait_for
from .test_screens import _ready
from .test_stale_lines import estop_refused_reset

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


def _toast_text(app) -> str:
    return " ".join(" ".join(str(t.render()).split()) for t in app.screen.query(Toast))


def _one_write(app, *keys: str) -> None:
    """``keys`` as one write of the terminal: queued together, none waiting for what the
    one before it set off (the pilot's ``press`` waits for the app between keys)."""
    for key in keys:
        event = events.Key(key, None)
        event.set_sender(app)
        app._driver.send_message(event)


def _bar(app) -> str:
    return " ".join(str(app.query_one("#safety").render()).split())


@SIZES
@pytest.mark.parametrize("initial", ["devices", "relays"])
def test_ctrl_e_then_ctrl_r_at_once_leaves_the_reset_s_notification(plugins, size, initial):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial=initial)
        said = spy_notifications(app)
        async with app.run_test(size=size, notifications=True) as pilot:
            await _ready(app, pilot)
            _one_write(app, "ctrl+e", "ctrl+r")  # `tmux send-keys C-e C-r`
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 20, "reset")
            await wait_for(pilot, lambda: "idle" in _bar(app), 10, "the bar idle")
            await pilot.pause(1.0)  # every echo of the two keys has come by now
            assert "e-stop reset" in _toast_text(app), (_toast_text(app), said)
            assert "E-STOP" not in _toast_text(app), (_toast_text(app), said)
            assert said[-1].startswith("e-stop reset"), said

    asyncio.run(scenario())


@SIZES
@pytest.mark.parametrize("key", ["f4", "f5", "f6", "f10"])
def test_the_estop_s_notification_stays_over_a_hidden_screen_s_status(plugins, size, key, caplog):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        said = spy_notifications(app)
        async with app.run_test(size=size, notifications=True) as pilot:
            # Devices says the e-stop and then its reset on its own line
            devices = await estop_refused_reset(app, pilot)
            await pilot.press(key)  # another screen
            await pilot.pause(0.5)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 20, "e-stopped again")
            # Devices, hidden, says the e-stop on its own line (and in the log)
            await wait_for(pilot, lambda: "e-stop active" in devices.result, 10, "Devices")
            await pilot.pause(0.5)
            assert _toast_text(app).startswith("E-STOP"), (_toast_text(app), said)
            shown = [str(n.message) for n in app._notifications]
            assert shown and shown[-1].startswith("E-STOP"), shown
        # what Devices said is in the log
        logged = [r.getMessage() for r in caplog.records]
        assert any(m.startswith("status Devices: e-stop active") for m in logged), logged

    asyncio.run(scenario())
