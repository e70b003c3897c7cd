"""A new-user trial (twin ``sim``): relay 1 on, then ``haptable play sweep`` in a shell:
relays 2-4 read ``[on ]`` and every row said "ready (switches only in silence)" while it
played; ``3`` then said "[on ] closed - waits to close". As the README says, a switch's
brackets are the operator's setting; the row says what the gate does (closed by the
sweep's routing, naming its command) and a toggle's wait says what is true."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
from pathlib import Path

import pytest
from textual.widgets import Switch

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for

ROOT = Path(__file__).resolve().parents[2]


def _row(app, ch: int) -> str:
    return " ".join(str(app.query_one(f"#interlock-{ch}").render()).split())


def _on(app, ch: int) -> bool:
    return app.query_one(f"#relay-{ch}", Switch).value


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_brackets_keep_the_operator_s_setting_while_a_sweep_routes(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("1")
            await wait_for(pilot, lambda: _on(app, 1) and "closed" in _row(app, 1), 10, "1 on")
            env = {**os.environ, "PYTHONPATH": str(ROOT)}
            proc = subprocess.Popen(
                [sys.executable, "-m", "console.cli.entry", "play", "sweep"],
                env=env,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            try:
                await wait_for(pilot, lambda: "closed" in _row(app, 2), 20, "the sweep routes")
                for ch in (2, 3, 4):
                    assert not _on(app, ch), ch  # the operator's setting: off
                    said = _row(app, ch)
                    assert said.startswith("closed by haptable play sweep (pid "), said
                    assert said.endswith(" - yours: open") and "ready" not in said, said
                assert _on(app, 1), _row(app, 1)
                assert _row(app, 1) == "closed - as yours; a toggle waits for sweep to end"
                await pilot.press("3")
                await pilot.pause(0.2)
                said = _row(app, 3)
                assert not said.startswith("closed - waits to close"), said
                assert said.endswith("yours waits to close until sweep ends"), said
                await asyncio.to_thread(proc.wait, 30)
                await wait_for(pilot, lambda: _on(app, 3), 10, "3 closes after the sweep")
                await wait_for(pilot, lambda: "open" in _row(app, 2), 10, "2 opens again")
                assert not _on(app, 2) and not _on(app, 4)
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait(10)

    asyncio.run(scenario())
