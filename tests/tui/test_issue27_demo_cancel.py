"""Issue 27: cancelling the flow demo while it prepares (Scenes screen, ``x``) stops its
process at once, in the middle of its preparation: the demo never comes up, what its
process started (the twin camera's process) ends with it, the console's outputs are
silent and not e-stopped, and the status says the start was cancelled (no numbers of a
run that never ran). How long the cancel takes is ``haptable bench demo-cancel``'s: this
checks where the process stopped."""

from __future__ import annotations

import asyncio
import os
from pathlib import Path

import pytest

from console.benchmarks.demo_cancel import descendants
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie has ended
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads /proc")
def test_x_while_the_flow_demo_prepares_ends_its_process_there(flow_ctx):
    from console.tui.long_work import LongWork

    async def scenario():
        app = HapTableApp(flow_ctx, fast=False, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            out = app.session.outputs
            await pilot.press("d")
            await pilot.press("enter")  # flow: the first row
            lw = app.query_one("#demo-work", LongWork)
            await wait_for(pilot, lambda: "opening the camera" in lw.text, 60, "its preparation")
            run = app.session.demos.run
            # the preparation has started processes of its own (the twin camera's)
            await wait_for(pilot, lambda: descendants(run.proc.pid), 30, "its first process")
            kids = descendants(run.proc.pid)
            await pilot.press("x")
            assert lw.text.startswith("cancelling demo flow") or lw.outcome == "cancelled"
            await wait_for(
                pilot,
                lambda: lw.outcome == "cancelled" and app.session.demos.run is None,
                30,
                "cancelled",
            )
            # it stopped inside its preparation: the demo never came up (before the fix
            # the preparation ran to its end, the demo started, then stopped)
            assert run.proc.wait(10) == 0
            assert run.scene_name is None, "the demo came up before the cancel took"
            assert run.final == {"reason": "cancelled", "estop": None}
            assert run.exit_reason == "cancelled"
            # nothing it started runs on
            await wait_for(pilot, lambda: not any(alive(p) for p in kids), 10, "its processes end")
            # the console's outputs: silent, relays open, not e-stopped
            await wait_for(pilot, lambda: app.session.outputs is out, 10, "outputs back")
            gate = out.status()["gate"]
            assert not out.estopped and gate["relays_closed"] == [] and not any(gate["level_v"])
            # the status follows the run's end at the pane's next refresh; the work line
            # says it was cancelled, the status only that it has no numbers (said once)
            await wait_for(
                pilot, lambda: "flow: no numbers" in words_on(app, "#demo-status"), 10, "status"
            )
            said = words_on(app, "#demo-status")
            assert "latency" not in said and "cancelled" not in said, said
            assert lw.text == "demo flow cancelled"
            table = app.query_one("#demo-table")
            assert str(table.get_cell("flow", "state")) == "cancelled"

    asyncio.run(scenario())
