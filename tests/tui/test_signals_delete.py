"""Delete on the Signals screen's library asks first: the first press names the signal
and says how to remove it, a second press on the same one removes it, anything else
keeps it; ctrl+z brings back the one just removed."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import OptionList, Static

from console.cli.main import Context
from console.config.signal_library import add_signal, library_path, read_library
from console.tui.app import HapTableApp

from .conftest import wait_for


def _status(app) -> str:
    return str(app.query_one("#sig-status", Static).render())


def _saved() -> set[str]:
    return {n for n, e in read_library(library_path("sim")).entries.items() if not e.builtin}


async def _on_saved(app, pilot, name: str) -> OptionList:
    await wait_for(pilot, lambda: app.query("#sig-library"), 10, "signals built")
    lib = app.query_one("#sig-library", OptionList)
    await wait_for(pilot, lambda: name in [o.id for o in lib.options], 10, "listed")
    await wait_for(pilot, lambda: "dominant" in _status(app), 20, "first preview's line")
    lib.focus()
    lib.highlighted = [o.id for o in lib.options].index(name)
    await pilot.pause(0.05)
    return lib


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_delete_asks_before_it_removes(plugins, size):
    add_signal(library_path("sim"), "my-tone", "sine(250 Hz, 20 V, 1 s) * ramp(10 ms)")
    add_signal(library_path("sim"), "other", "silence(1 s)")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            lib = await _on_saved(app, pilot, "my-tone")
            await pilot.press("delete")
            assert "my-tone" in _saved()  # nothing removed yet ...
            assert "delete again to remove 'my-tone'" in _status(app).lower()  # ... it asks
            await pilot.press("down")  # the operator moves on: the question lapses
            await pilot.press("up")
            await pilot.press("delete")
            assert "my-tone" in _saved()
            await pilot.press("delete")  # asked, and confirmed on the same signal
            await wait_for(pilot, lambda: "my-tone" not in _saved(), 5, "removed")
            assert "removed my-tone" in _status(app)
            assert "my-tone" not in [o.id for o in lib.options]
            assert "other" in _saved()

    asyncio.run(scenario())


def test_ctrl_z_brings_back_a_removed_signal(plugins):
    expr = "sine(250 Hz, 20 V, 1 s) * ramp(10 ms)"
    add_signal(library_path("sim"), "my-tone", expr)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=(120, 40)) as pilot:
            lib = await _on_saved(app, pilot, "my-tone")
            await pilot.press("delete", "delete")
            await wait_for(pilot, lambda: "my-tone" not in _saved(), 5, "removed")
            assert "ctrl+z" in _status(app)  # the status says how to bring it back
            await pilot.press("ctrl+z")
            await wait_for(pilot, lambda: "my-tone" in _saved(), 5, "restored")
            assert read_library(library_path("sim")).entries["my-tone"].expr == expr
            assert "my-tone" in [o.id for o in lib.options]

    asyncio.run(scenario())
