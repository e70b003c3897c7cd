"""The Electrostatic screen says what happened to a setting it was asked to play, after
it happened (issue 27): asking, then playing once the outputs report its start, then
played; during an e-stop refused with the fix, never "playing" first."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_screens import _ready


def _status(app) -> str:
    return str(app.query_one("#es-status").render())


def _said(app, seen: list[str]) -> list[str]:
    return seen + [str(n.message) for n in app._notifications]


def _spy(pane) -> list[str]:
    seen: list[str] = []
    real = pane.say

    def spy(text, *a, **kw):
        seen.append(text)
        return real(text, *a, **kw)

    pane.say = spy
    return seen


def test_p_during_an_estop_is_refused_never_playing(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="electrostatic")
        async with app.run_test(size=(80, 24), notifications=True) as pilot:
            await _ready(app, pilot)
            pane = app.pane("electrostatic")
            seen = _spy(pane)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, what="e-stopped")
            await pilot.press("p")
            await wait_for(pilot, lambda: "refused" in _status(app), 20, "refusal")
            assert "refused: e-stop active, ctrl+r resets" in _status(app)
            assert not any("playing" in t for t in _said(app, seen)), _said(app, seen)
            assert app.session.played == []
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, what="reset")
            await wait_for(pilot, lambda: "refused" not in _status(app), 10, "cleared")

    asyncio.run(scenario())


def test_p_says_asking_then_playing_then_played(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="electrostatic")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("electrostatic")
            seen = _spy(pane)
            await pilot.press("p")
            await wait_for(pilot, lambda: _status(app).startswith("played"), 30, "played")
            asks = [i for i, t in enumerate(seen) if t.startswith("asking to play")]
            plays = [i for i, t in enumerate(seen) if t.startswith("playing")]
            assert asks and plays and asks[0] < plays[0], seen
            assert "on the screen" in _status(app)

    asyncio.run(scenario())


def test_a_condition_without_haptics_says_the_outputs_stay_at_zero(plugins):
    """Knob V is visual only: the line says so instead of a bare "playing"."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="electrostatic")
        async with app.run_test(size=(120, 40)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("electrostatic")
            seen = _spy(pane)
            pane._play_condition("V")
            await wait_for(pilot, lambda: any("no haptic feedback" in t for t in seen), 20)
            pane._play_condition("HD")
            await wait_for(pilot, lambda: any("knob HD:" in t for t in seen), 20)
            assert not any("knob HD:" in t and "no haptic" in t for t in seen)

    asyncio.run(scenario())
