"""A console that closes on an error (a handler raised) exits with status 3, the
README's internal error, and closes its session on the way out (outputs silenced);
one the operator quits exits 0. A new operator's crash exited 0."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp, exit_status

from .conftest import wait_for


def test_a_console_closed_by_an_error_exits_3_with_its_session_closed(plugins):
    app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")

    def boom() -> None:
        raise RuntimeError("a handler's mistake")

    async def scenario():
        try:
            async with app.run_test(size=(80, 24)) as pilot:
                await wait_for(pilot, lambda: app.session.outputs is not None, what="outputs")
                await pilot.press("1")  # relay 1 closed: a live output when it fails
                await wait_for(pilot, lambda: app.session.outputs.relay_state() == {1})
                app.call_later(boom)
                await wait_for(pilot, lambda: not app.is_running, 30, "closed")
        except RuntimeError:
            pass  # the pilot hands the app's exception on

    asyncio.run(scenario())
    assert exit_status(app) == 3
    # the outputs closed: the table's kernel silences and opens what a closed
    # connection played (tests/kernel)
    assert app.session._closing
    assert app.session.outputs is None or app.session.outputs.closed


def test_a_console_the_operator_quits_exits_0(plugins):
    app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")

    async def scenario():
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.focused is not None, what="focus")
            await pilot.press("q")
            await pilot.pause(0.2)
            if app.is_running:
                await pilot.press("q")  # a second q when the first one asks
            await wait_for(pilot, lambda: not app.is_running, 30, "quit")

    asyncio.run(scenario())
    assert exit_status(app) == 0
