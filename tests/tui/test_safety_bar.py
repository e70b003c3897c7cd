"""The safety bar stays readable: notifications never cover it, and at 80 x 24 it still
shows the closed relays and the e-stop / reset key (an operator's first look after an
e-stop or an audition)."""

from __future__ import annotations

import asyncio
import re

from textual.widgets._toast import Toast

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.safety_bar import SafetyBar, describe

from .conftest import wait_for


def _status(*, estopped=False, reason="", relays=(), level=(0.0, 0.0), busy=False):
    gate = {
        "estopped": estopped,
        "estop_reason": reason,
        "relays_closed": list(relays),
        "level_v": level,
    }
    return {"gate": gate, "busy": busy}


def test_the_bar_keeps_relays_and_keys_at_any_width():
    for width in (200, 120, 80, 60):
        text, cls = describe(_status(relays=(1, 2, 3, 4, 5), level=(-123.4, 300.0)), width)
        assert len(text) <= width and cls == "idle"
        assert "E-STOP" in text and "1,2,3,4,5" in text
        long_reason = "e-stop from another process: the demo's watchdog tripped in stage vision"
        text, cls = describe(_status(estopped=True, reason=long_reason, relays=(5,)), width)
        assert len(text) <= width and cls == "estop"
        assert "ctrl+r" in text and "relays closed: 5" in text
        five = _status(relays=(1, 2, 3, 4), level=(-123.4, 0.0, 56.7, 0.0, 300.0))
        five["gate"]["channels"] = ["PA", "PB", "PC", "PD", "screen"]
        text, _ = describe(five, width)
        assert len(text) <= width and "E-STOP" in text and "1,2,3,4" in text
        if width >= 80:  # every channel by name
            assert all(n in text for n in ("PA", "PB", "PC", "PD", "screen")), text
    for width in (80, 72, 66):  # playing at a narrow width: every level keeps its unit
        text, _ = describe(_status(relays=(1,), level=(-10.2, 0.0), busy=True), width)
        levels = re.findall(r"(?:piezo|screen) ([+-][0-9.]+)( V)?", text)
        assert levels and all(unit for _v, unit in levels), text
    wide, _ = describe(_status(estopped=True, reason="operator", relays=()), 200)
    assert "operator" in wide and "relays closed: none" in wide


def test_notifications_never_cover_the_bar_at_80x24(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24), notifications=True) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            bar = app.query_one(SafetyBar)
            await pilot.press("1")  # close relay 1, then e-stop: it opens again
            await wait_for(pilot, lambda: "relays closed: 1" in str(bar.render()))
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped)
            await wait_for(pilot, lambda: bool(app.screen.query(Toast)), what="a toast")
            await wait_for(pilot, lambda: "ctrl+r" in str(bar.render()))
            text = str(bar.render())
            assert "relays closed: none" in text and len(text) <= 80
            await pilot.pause(0.3)  # the toasts are laid out
            for toast in app.screen.query(Toast):
                assert not toast.region.overlaps(bar.region), (toast.region, bar.region)
            # what the operator sees on the bar's row is the bar
            row = bar.region.y
            for x in (1, 40, 79):
                widget, _ = app.screen.get_widget_at(x, row)
                assert widget is bar, (x, widget)
            # ctrl+r resets the e-stop; again, with none latched, it says so (not silence)
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            await pilot.press("ctrl+r")
            await wait_for(
                pilot,
                lambda: any(
                    "no e-stop to reset" in str(t.render()) for t in app.screen.query(Toast)
                ),
                what="the no-e-stop toast",
            )

    asyncio.run(scenario())


def test_the_bar_shows_on_the_help_and_the_log(plugins):
    """A modal (help, the log view) shows the bar too, kept up to date: an e-stop
    pressed there shows at once, with the reset key and the relays."""
    from console.tui.logs import LogScreen

    from .test_literal_text import screen_text

    app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")

    def last() -> str:
        return screen_text(app).splitlines()[-2]  # the bar: where the main one is

    async def scenario():
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            for key, modal in (("question_mark", "HelpScreen"), ("ctrl+l", LogScreen.__name__)):
                await pilot.press(key)
                await wait_for(pilot, lambda m=modal: type(app.screen).__name__ == m, 5, modal)
                await pilot.press("ctrl+e")
                await wait_for(pilot, lambda: app.session.outputs.estopped)
                await wait_for(
                    pilot, lambda: "E-STOP: operator" in last(), 5, f"the bar: {last()!r}"
                )
                assert "relays closed: none" in last() and "ctrl+r" in last()
                await pilot.press("ctrl+r")
                await wait_for(pilot, lambda: "| idle |" in last(), 5, "the bar idle")
                await pilot.press("escape")
                await wait_for(pilot, lambda: app.screen is app.base, 5, "back")

    asyncio.run(scenario())


def test_a_level_that_shows_as_zero_has_no_sign():
    """After a ramp down the last sample can be -1e-9 V: the bar says +0.0 V, not -0.0 V."""
    for width in (None, 80, 40):
        text, _ = describe(_status(level=(-1e-9, -0.0)), width)
        assert "-0" not in text, text


def test_the_command_palette_leaves_the_bar_in_view_at_80x24(plugins):
    """ctrl+p covers the screen with its list: the bar's row still shows the output
    state, and follows an e-stop from another process while the palette is open."""
    from .test_camera_layout import screen_lines

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs open")
            await pilot.press("ctrl+p")
            await wait_for(pilot, lambda: len(app.screen_stack) > 1, what="the palette")
            await pilot.pause(0.5)  # the list of every command, down the screen
            await wait_for(pilot, lambda: "E-STOP" in screen_lines(app)[-2], what="bar row")
            app.session.outputs.estop("test: another process")
            await wait_for(pilot, lambda: "ctrl+r" in screen_lines(app)[-2], what="e-stop shown")

    asyncio.run(scenario())
