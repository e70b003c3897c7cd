"""Signals (F8) at 80 x 24: its status line says what is true. A signal the gate refuses
is refused up front (as ``haptable signals play --dry-run``) and never announced as
"playing"; "playing" shows only once the outputs report the start. Enter on a library
signal over a typed, unsaved expression asks first (the question lapses with its
window), and ctrl+z brings the expression back."""

from __future__ import annotations

import asyncio

from textual.widgets import Input, OptionList

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for

SIZE = (80, 24)
REFUSED = "lowpass((square(200 Hz, 50 V, 0.5 s)) * ramp(5 ms), 1 kHz)"
GOOD = "sine(300 Hz, 10 V, 0.2 s) * ramp(5 ms)"


async def _pane(app, pilot):
    """Signals once the outputs are open and its library listed: (the pane, every line
    its status says from now on, in order)."""
    pane = app.pane("signals")
    await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
    await wait_for(pilot, lambda: bool(pane.entries), 10, "library")
    lines: list[str] = []
    said = pane.status

    def status(text: str, error: bool = False) -> None:
        lines.append(" ".join(str(text).split()))
        said(text, error)

    pane.status = status
    return pane, lines


def _fields(app, expr: str, name: str, target: str) -> None:
    for wid, text in (("#sig-expr", expr), ("#sig-name", name), ("#sig-target", target)):
        app.query_one(wid, Input).value = text


def test_a_refused_signal_is_never_said_to_play(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=SIZE) as pilot:
            pane, lines = await _pane(app, pilot)
            _fields(app, REFUSED, "mysig", "PA,PC")
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: any("not 0" in x for x in lines), 30, str(lines))
            await pilot.pause(0.3)
            assert not any(x.startswith("playing") for x in lines), lines
            assert "starts at" in lines[-1] and "ramp(" in lines[-1], lines
            # a signal the gate takes: checked, then playing once started, then played
            lines.clear()
            _fields(app, GOOD, "good", "PA")
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: any(x.startswith("played") for x in lines), 30, "")
            states = [x.split()[0] for x in lines]
            assert states.index("checking") < states.index("playing") < states.index("played")

    asyncio.run(scenario())


def test_enter_on_a_library_signal_keeps_a_typed_expression(plugins, monkeypatch):
    import console.tui.panes.signals as sp

    monkeypatch.setattr(sp, "LOAD_AGAIN_S", 1.0)  # the window, shorter for the test

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=SIZE) as pilot:
            pane, lines = await _pane(app, pilot)
            _fields(app, GOOD, "", "PA")
            library = app.query_one("#sig-library", OptionList)
            library.focus()
            target = next(n for n, e in pane.entries.items() if e.expr.strip() != GOOD)
            library.highlighted = list(pane.entries).index(target)
            await pilot.press("enter")
            await pilot.pause(0.1)
            assert app.query_one("#sig-expr", Input).value == GOOD  # not replaced
            assert f"enter again within 1 s loads {target} over your unsaved" in lines[-1]
            await wait_for(pilot, lambda: "stays in the fields" in lines[-1], 5, "lapsed")
            await pilot.press("enter")  # the window passed: it asks again
            await pilot.pause(0.1)
            assert app.query_one("#sig-expr", Input).value == GOOD, lines
            await pilot.press("enter")
            await wait_for(pilot, lambda: lines[-1].startswith(f"loaded {target}"), 10, "")
            assert app.query_one("#sig-expr", Input).value == pane.entries[target].expr
            assert "ctrl+z brings it back" in lines[-1], lines[-1]
            await pilot.press("ctrl+z")
            await wait_for(pilot, lambda: "your expression is back" in lines[-1], 10, "")
            assert app.query_one("#sig-expr", Input).value == GOOD

    asyncio.run(scenario())
