"""Vibration (F3) with no map while ``haptable study run exp1 ... --simulate`` runs in a
shell (issue 27, "visible and truthful"): the line kept saying ``no vibration map: press
m to measure ...`` and ``m`` was refused (the run plays on the profile's map). The line's
advice comes from the check ``m`` makes: it names the run and how to end it, never the
refused key. 80x24 and 120x40."""

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


def _line(app) -> str:
    return text_in(app, app.query_one("#vib-status"))


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_no_map_line_names_the_run_not_a_refused_key(plugins, size, tmp_path):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), initial="vibration")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: "press m" in _line(app), 30, "no map, press m")
            cmd = ["study", "run", "exp1", "--participant", "P01", "--out", str(tmp_path)]
            proc = subprocess.Popen(
                [sys.executable, "-m", "console.cli.entry", *cmd, "--simulate"],
                env={**os.environ, "PYTHONPATH": str(ROOT)},
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            try:
                await wait_for(pilot, lambda: f"pid {proc.pid}" in _line(app), 60, "the run")
                said = _line(app)
                assert "press m" not in said and "stop it there first" in said, said
                await pilot.press("m")  # refused, as the line said
                await wait_for(pilot, lambda: "measure refused" in _line(app), 10, "refused")
                proc.terminate()
                await asyncio.to_thread(proc.wait, 30)
            finally:
                if proc.poll() is None:
                    proc.kill()
                    proc.wait(10)

    asyncio.run(scenario())
