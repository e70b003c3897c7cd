"""A new operator's try: Devices `s` asked "s again within 3 s runs the self-test: a
chirp on every relay path" and said its paths and seconds only once it had started. The
question says them (from `haptable selftest --estimate`), as every long work does before
it starts; nothing plays until `s` comes again."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.panes import devices_selftest as devices_mod
from console.tui.selftest_action import selftest_estimate

from .conftest import wait_for, words_on


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_s_says_the_paths_and_seconds_before_it_runs(plugins, monkeypatch, size):
    ran: list[bool] = []
    monkeypatch.setattr(
        devices_mod, "run_selftest", lambda p, pm: (ran.append(True), (True, "ok"))[1]
    )

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            said = lambda: words_on(app, "#devices-result")  # noqa: E731
            est = selftest_estimate(app.ctx.profile, app.ctx.pm)
            assert est is not None
            await pilot.press("s")
            await wait_for(pilot, lambda: "s again within 3 s" in said(), 10, "asked")
            assert f"{est[1]} relay paths, {est[0]:.0f} s of chirps" in said(), said()
            await pilot.pause(0.3)
            assert ran == []  # asked only

    asyncio.run(scenario())
