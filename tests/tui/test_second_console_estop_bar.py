"""A second console of a profile another console runs (its bar: `not open: another
console already runs profile 'sim' ...`): after its own ctrl+e the table is e-stopped,
and its bar says so, as every bar does (E-STOP, the reason, where it resets), until the
console holding the outputs resets it (a new operator's try: the bar kept saying `not
open: another console ...` while the table was e-stopped)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.session import ConsoleSession
from console.tui.app import HapTableApp
from console.tui.safety_bar import SafetyBar

from .conftest import wait_for


def _bar(app) -> str:
    return str(app.screen.query_one(SafetyBar).render())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_second_consoles_bar_shows_the_estop_it_made(plugins, size):
    first = ConsoleSession(Context("sim", plugins), fast=False)  # the table's own console
    assert first.open_outputs()

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: "another console" in _bar(app), 30, "not open")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: first.outputs.estopped, 20, "the table e-stopped")
            await wait_for(pilot, lambda: _bar(app).startswith(" E-STOP"), 10, "the E-STOP")
            bar = _bar(app)
            assert "reset in the console holding the outputs" in bar, bar  # where it resets
            assert "operator e-stop" in bar, bar  # why, in the console's words (the latch)
            assert "haptable estop" not in bar, bar  # not a shell's e-stop
            assert "ctrl+r: reset" not in bar, bar  # not offered where it resets nothing
            assert len(bar.rstrip()) <= size[0], bar
            assert "estop" in app.screen.query_one(SafetyBar).classes
            assert first.reset_estop()  # the console holding the outputs resets it
            await wait_for(
                pilot, lambda: not _bar(app).startswith(" E-STOP"), 10, "the reset shown"
            )
            assert "another console" in _bar(app), _bar(app)

    try:
        asyncio.run(scenario())
    finally:
        first.close()
