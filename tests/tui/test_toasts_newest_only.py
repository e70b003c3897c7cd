"""One notification on the title row, the newest, whatever said it (a new operator at
80 x 24 saw a watchdog's e-stop toast cut mid-word beside the reset's, and the e-stop's
stayed after the reset): an e-stop latched elsewhere (the kernel, as a demo's watchdog
latches it), a refusal, the operator's ctrl+r."""

from __future__ import annotations

import asyncio

from textual.notifications import Notification
from textual.widgets._toast import Toast, ToastHolder

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_screens import _ready

WATCHDOG = (
    "runtime watchdog: frame loop stalled 261 ms in camera "
    "(limit [runtime] watchdog_ms = 250); outputs silenced"
)


def _said(app) -> list[str]:
    return [str(n.message) for n in app._notifications]


def _top(app) -> str:
    return app.screen._compositor.render_strips()[0].text


def test_the_newest_notification_replaces_the_estop_and_goes_with_the_reset(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24), notifications=True) as pilot:
            await _ready(app, pilot)
            # latched through the session's kernel client, as the watchdog does
            app.session.outputs.estop(WATCHDOG)
            await wait_for(pilot, lambda: "E-STOP: runtime" in _top(app), 30, "the toast")
            await pilot.press("f1")
            await pilot.press("t")
            pane = app.pane("devices")
            await wait_for(pilot, lambda: "refused" in pane.result, 20, "refused")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 20, "reset")
            await wait_for(pilot, lambda: "e-stop reset" in _top(app), 20, "reset said")
            await pilot.pause(0.5)
            top = _top(app)
            assert "E-STOP" not in top, top
            assert not any("E-STOP" in m for m in _said(app)), _said(app)
            assert len(_said(app)) == 1, _said(app)
            toasts = [t for t in app.screen.query(Toast) if t.region]
            assert len(toasts) == 1 and len(app.screen.query(ToastHolder)) == 1, toasts

    asyncio.run(scenario())


def test_an_estop_right_after_a_reset_shows_alone(plugins):
    """ctrl+e, ctrl+r, ctrl+e within a second: the title row shows the e-stop alone (the
    reset's toast stayed beside it for seconds)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24), notifications=True) as pilot:
            await _ready(app, pilot)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 20, "e-stop")
            await pilot.press("ctrl+r")
            await pilot.pause(0.1)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: "E-STOP" in _top(app), 20, "the e-stop's toast")
            for _ in range(10):
                await pilot.pause(0.1)
                top = _top(app)
                assert "reset" not in top, top
                toasts = [t for t in app.screen.query(Toast) if t.region]
                assert len(toasts) <= 1, top
            # notifications in one burst (the kernel's events and the keys' own, as a
            # loaded console delivers them): the last alone on the row, once drawn
            app.notify("e-stop reset: outputs may play again")
            app.notify("E-STOP: outputs silenced, relays open", severity="error")
            app.notify("e-stop reset: outputs may play again")
            app.notify("E-STOP: outputs silenced, relays open", severity="error")
            for _ in range(10):
                await pilot.pause(0.05)
            top = _top(app)
            assert "E-STOP" in top and "reset" not in top, top
            assert len(app.screen.query(ToastHolder)) == 1, top

    asyncio.run(scenario())


def test_a_notification_while_the_console_closes_is_dropped(plugins):
    """A status said while the console closes (a demo's last word after ``q``) finds no
    screen: it is dropped, not raised from the message loop (one pilot run failed so:
    'No screens on stack')."""
    from textual.notifications import Notify

    app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
    app._on_notify(Notify(Notification("demo stopped", "", "information", 3)))
    assert not app._notifications
