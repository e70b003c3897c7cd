"""Vibration (F3): Enter during a 3 s hand flow (``d``) queued the point, but the flow's
own end (played or cut short) was never said nor logged (issue 27, "visible and
truthful"): the point's line took over and the flow vanished. The flow's end is said on
the screen's line (and so in the log) before the point plays. Pilot at 80x24 and
120x40."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import command, wait_for, words_on


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_hand_flow_s_end_is_said_when_enter_queued_a_point(plugins, map_file, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=False, initial="vibration")
        async with app.run_test(size=size) as pilot:
            pane = app.pane("vibration")
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            await command(app, pilot, f"load {map_file}")
            await wait_for(pilot, lambda: pane.session is not None, 30, "map loaded")
            said: list[str] = []
            status = pane.status

            def keep(text: str, *args, **kwargs) -> None:
                said.append(text)
                status(text, *args, **kwargs)

            pane.status = keep
            s = pane.session  # a point where a hand fits (a hand flow plays there)
            n = next(
                int(s.vmap.points[i])
                for i, p in enumerate(s.vmap.points_mm)
                if s.hand_fits((float(p[0]), float(p[1])))
            )
            pane.move_cursor(n)
            await pilot.pause(0.2)
            await pilot.press("d")
            line = lambda: words_on(app, "#vib-status")  # noqa: E731
            await wait_for(pilot, lambda: "playing hand flow" in line(), 60, "flow playing")
            flow = line().removeprefix("playing ").split(":")[0]
            await pilot.press("enter")  # a point, queued behind the flow
            await wait_for(pilot, lambda: "playing point" in line(), 60, "point playing")
            ends = [s for s in said if s.startswith(f"played {flow}") or "stopped" in s]
            assert ends, said
            at = said.index(ends[0])
            assert any(s.startswith("playing point") for s in said[at:]), said

    asyncio.run(scenario())
