"""Issue 27, fourth new-user try: Scope's ``p`` shows the last plan whole after the
scope's ring moved on, whoever sent it (a CLI plan is copied when it ends, as this
console's own are, even while the Scope screen is not shown); a frozen view's header
follows the plan's state (it kept "(playing)" after an e-stop until unfrozen)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_scope_any_sender import _cli

LONG = "sine(100 Hz, 5 V, 6 s) * ramp(10 ms)"


async def _cli_plays(app, pilot, proc) -> None:
    def playing() -> bool:
        last = app.session.last_plan()
        return last is not None and not last.own and not last.done and bool(last.segment_start)

    await wait_for(pilot, playing, 30, "the CLI's plan plays")


def test_p_shows_a_cli_plan_whole_after_the_ring_moved_on(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="signals")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            proc = _cli("signals", "play", LONG, "--patch", "PA")
            try:
                await _cli_plays(app, pilot, proc)
                start = app.session.last_plan().segment_start[0]
                await pilot.pause(1.0)
                await pilot.press("ctrl+e")
                assert proc.wait(30) == 4

                def ring_moved_on() -> bool:
                    whole = app.session.scope(None)
                    return whole is not None and whole.clock > start

                await wait_for(pilot, ring_moved_on, 30, "the plan's start leaves the ring")
                await pilot.press("f9")
                await pilot.press("p")
                head = lambda: words_on(app, "#scope-head")  # noqa: E731
                info = lambda: words_on(app, "#scope-info")  # noqa: E731
                await wait_for(pilot, lambda: "FROZEN ON THE LAST PLAN" in head(), 30, "p")
                assert "gone" not in head(), head()
                assert f"from the CLI (pid {proc.pid})" in head(), head()
                assert "estop at " in info(), info()
                assert "piezo 5.0 V" in info(), info()  # its 5 V, not a flat line
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait()

    asyncio.run(scenario())


def test_a_frozen_header_follows_the_plan_to_its_end(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="scope")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            proc = _cli("signals", "play", LONG, "--patch", "PA")
            try:
                await _cli_plays(app, pilot, proc)
                head = lambda: words_on(app, "#scope-head")  # noqa: E731
                await wait_for(pilot, lambda: "(playing)" in head(), 30, "playing shown")
                await pilot.press("space")
                await wait_for(pilot, lambda: head().startswith("FROZEN |"), 30, "frozen")
                await pilot.press("ctrl+e")
                assert proc.wait(30) == 4
                await wait_for(pilot, lambda: "(stopped: " in head(), 30, f"its end: {head()}")
                assert head().startswith("FROZEN |") and "(playing)" not in head()
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait()

    asyncio.run(scenario())
