"""The console as a process of its own, for the kill -9 test: the Studies screen starts
experiment 2 for a simulated participant (the observer double) and runs until killed.

``python console_child.py OUT MAP``; with ``HAPTABLE_TEST_HANG_AT`` set, the double hangs
at that trial (the trial in flight when the test kills this process)."""

from __future__ import annotations

import asyncio
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))


async def _console(out: str, map_file: str) -> None:
    from console.cli.main import Context
    from console.config import plugins as cp
    from console.tui.app import HapTableApp

    cp.BUILTIN_PLUGINS["double"] = "observer_double"
    app = HapTableApp(Context("sim", cp.load_plugins()), fast=True, initial="studies")
    async with app.run_test(size=(120, 40)) as pilot:
        while app.session.outputs is None or app.pane("studies") is None:
            await pilot.pause(0.05)
        await asyncio.to_thread(app.session.vibration.load, Path(map_file))
        pane = app.pane("studies")
        pane.query_one("#protocol").value = "exp2"
        pane.query_one("#out").value = out
        await pilot.click("#start")  # 200 trials, about 10 min: it asks first
        await pilot.pause(0.2)
        await pilot.click("#start")  # again within the 5 s: it starts
        while True:  # until killed
            await pilot.pause(0.2)


if __name__ == "__main__":
    asyncio.run(_console(sys.argv[1], sys.argv[2]))
