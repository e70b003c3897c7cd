"""Relays (F4) after an e-stop during a study run and a reset (issue 27, "visible and
truthful"): rows whose setting is ``[off]`` said ``the e-stop opened it; press 1 to close
again``, though the study's plan (not the operator) had closed them. A row says who
closed it, that the e-stop opened it, and names the key only for the operator's own
setting (pressing brings that back). Pilot at 80x24 and 120x40."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.session.audition import audition_plan
from console.signals.design import parse_target
from console.tui.app import HapTableApp

from .conftest import wait_for

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


def _row(app, ch: int) -> str:
    return " ".join(str(app.query_one(f"#interlock-{ch}").render()).split())


@SIZES
def test_a_relay_the_run_closed_is_not_said_to_be_the_operator_s(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("3")  # the operator's own setting: relay 3 on
            await wait_for(pilot, lambda: _row(app, 3).startswith("closed - ready"), 30, "3")
            plan = audition_plan(
                app.ctx.profile,
                "sine(250 Hz, 5 V, 4 s) * ramp(20 ms)",
                parse_target("PA"),
                "trial 7",
            )
            who = "P01's study run of exp1 (Studies screen)"
            with app.session.hold_outputs(who) as token:
                assert app.session.play_plan(plan, wait=False, holder=token)
                await wait_for(pilot, lambda: _row(app, 1).startswith("closed by"), 30, "routed")
                await pilot.press("ctrl+e")
                await wait_for(pilot, lambda: app.session.outputs.estopped, 30, "e-stopped")
            await pilot.press("ctrl+r")
            await wait_for(pilot, lambda: not app.session.outputs.estopped, 30, "reset")
            await wait_for(pilot, lambda: "e-stop opened it" in _row(app, 3), 30, "3 said")
            assert "press 3 to close again" in _row(app, 3), _row(app, 3)
            await wait_for(pilot, lambda: "e-stop opened it" in _row(app, 1), 10, "1 said")
            row = _row(app, 1)
            assert "press 1" not in row, row
            assert "trial 7" in row and "closed it" in row, row
            assert "yours: open" in row, row

    asyncio.run(scenario())
