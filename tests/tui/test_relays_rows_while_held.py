"""Relays (F4) while another run holds the outputs (issue 27, "visible and truthful"):
with ``haptable study run exp1 --participant P01 --out DIR --simulate`` in a shell every
row still said ``ready (switches only in silence)`` though any toggle was refused, and
after an e-stop during the console's own study run a row said ``the e-stop opened it;
press 3 to close again`` though that toggle was refused. The rows and their advice come
from the check the toggle makes (``ConsoleSession.held_why``, the e-stop): the hold, who
holds, how to end it; never a key that will be refused. Pilot at 80x24 and 120x40."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
from pathlib import Path

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import text_in

ROOT = Path(__file__).resolve().parents[2]
SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


def _seen(app, selector: str) -> str:
    return text_in(app, app.query_one(selector))


def _row(app, ch: int) -> str:
    return " ".join(str(app.query_one(f"#interlock-{ch}").render()).split())


@SIZES
def test_rows_say_a_shell_study_run_holds_the_outputs(plugins, size, tmp_path):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: "ready" in _row(app, 2), 30, "ready")
            cmd = ["study", "run", "exp1", "--participant", "P01", "--out", str(tmp_path)]
            proc = subprocess.Popen(
                [sys.executable, "-m", "console.cli.entry", *cmd, "--simulate"],
                env={**os.environ, "PYTHONPATH": str(ROOT)},
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            try:
                await wait_for(pilot, lambda: app.session.held_why(), 60, "the run holds")
                await wait_for(pilot, lambda: "ready" not in _row(app, 2), 10, "rows follow")
                for ch in range(1, 9):
                    row = _row(app, ch)
                    assert "ready" not in row and "press" not in row, row
                    assert "refused" in row or "held" in row, row
                # who holds, and how to end it, in view (once laid out)
                await wait_for(pilot, lambda: "pid" in _seen(app, "#relays-held"), 10, "line")
                held = _seen(app, "#relays-held")
                assert f"pid {proc.pid}" in held and "study run of exp1" in held, held
                assert "stop it there first" in held, held
                proc.terminate()
                await asyncio.to_thread(proc.wait, 30)
                await wait_for(pilot, lambda: "ready" in _row(app, 2), 10, "ready again")
                assert not app.query_one("#relays-held").display
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait(10)

    asyncio.run(scenario())


@SIZES
def test_after_an_estop_in_a_console_run_no_row_names_a_refused_key(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), initial="relays")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("3")
            await wait_for(pilot, lambda: _row(app, 3).startswith("closed"), 30, "closed")
            # as the Studies screen's run holds them (a paused run holds them too)
            with app.session.hold_outputs("P01's study run of exp1 (Studies screen)"):
                await pilot.press("ctrl+e")
                await wait_for(pilot, lambda: app.session.outputs.estopped, 30, "e-stopped")
                await pilot.press("ctrl+r")
                await wait_for(pilot, lambda: not app.session.outputs.estopped, 30, "reset")
                await wait_for(pilot, lambda: "e-stop opened it" in _row(app, 3), 30, "said")
                row = _row(app, 3)
                assert "press 3" not in row and "held" in row, row
                await wait_for(pilot, lambda: "P01" in _seen(app, "#relays-held"), 10, "line")
                held = _seen(app, "#relays-held")
                assert "P01's study run of exp1" in held and "stop it first" in held, held
                await pilot.press("3")  # refused, as the row said
                await wait_for(pilot, lambda: "refused" in _row(app, 3), 10, "refused")
            # the hold ended: its refusal goes, the key that now works is named
            await wait_for(pilot, lambda: "press 3 to close" in _row(app, 3), 10, "free")
            assert "refused" not in _row(app, 3), _row(app, 3)

    asyncio.run(scenario())
