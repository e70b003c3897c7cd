"""A second console of a profile another console runs (its bar: `not open: another
console already runs profile 'sim' ...`): its ctrl+e e-stops the table, and its ctrl+r,
which the footer promises too, says why it resets nothing there and where it does (a new
operator's try: no status, no toast, no log line)."""

from __future__ import annotations

import asyncio
import os

import pytest

from console.cli.main import Context
from console.session import ConsoleSession
from console.tui.app import HapTableApp

from .conftest import spy_notifications, wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_ctrl_r_in_a_second_console_names_where_the_reset_is(plugins, size):
    first = ConsoleSession(Context("sim", plugins), fast=False)  # the table's own console
    assert first.open_outputs()

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        said = spy_notifications(app)
        async with app.run_test(size=size, notifications=True) as pilot:
            await wait_for(pilot, lambda: "another console" in app.session.outputs_error, 30)
            await pilot.press("ctrl+r")  # nothing e-stopped yet
            await wait_for(pilot, lambda: said, 10, "ctrl+r answered")
            assert said[-1] == "no e-stop to reset: table sim is not e-stopped", said
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: first.outputs.estopped, 20, "the table e-stopped")
            said.clear()
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: said, 10, "ctrl+r answered")
            assert said == [
                f"not reset here: ctrl+r in the console holding the outputs (pid {os.getpid()}), "
                "or `haptable --profile sim reset` at a terminal"
            ], said
            await pilot.pause(0.5)
            assert first.outputs.estopped  # still: only its own console resets it
            assert first.reset_estop()  # there it does

    try:
        asyncio.run(scenario())
    finally:
        first.close()


def test_ctrl_r_without_outputs_says_why_while_they_open_or_failed(profile):
    from console.kernel.tables import clear_latch, latch_record, table_for, write_latch
    from console.session.reset_here import no_reset_here

    table = table_for(profile.path)
    write_latch(table, latch_record("haptable estop (pid 12) from a shell", "estop"))
    try:
        opening = no_reset_here(profile, "", False)
        assert (
            opening
            == "ctrl+r: the outputs are still opening; press it again once the bar shows them"
        )
        failed = no_reset_here(profile, "no kernel: [audio] device gone", False)
        assert failed == (
            "ctrl+r resets nothing here: the outputs are not open (no kernel: [audio] device "
            "gone); `haptable --profile sim reset` at a terminal"
        )
    finally:
        clear_latch(table)
    assert no_reset_here(profile, "", False) == "no e-stop to reset: table sim is not e-stopped"
