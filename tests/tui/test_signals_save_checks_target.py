"""Signals (F8): ctrl+s saved a mistyped target (issue 27, "visible and truthful"): name
``mysig``, target ``PZ``, ctrl+s said ``saved mysig for no channel ('PZ' names none)``
while ctrl+o refused ``PZ`` (``unknown patch 'PZ'``) and ``haptable signals add ...
--target PZ`` exited 2. Save, play and the CLI check a target with one function
(``console.signals.design.parse_target``): the save is refused with the same line, naming
the patches that exist. Pilot at 80x24 and 120x40; the CLI through a subprocess."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
from pathlib import Path

import pytest

from console.cli.main import Context
from console.config.signal_library import library_path, read_library
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_signals_truthful_lines import _fields, _pane

ROOT = Path(__file__).resolve().parents[2]
EXPR = "sine(250 Hz, 5 V, 0.2 s) * ramp(10 ms)"
REFUSAL = (
    "target 'PZ': unknown patch 'PZ'; use PA, PB, PC, PD, PALL or screen (combine patches as PA,PC)"
)


def _cli_refusal() -> str:
    """What ``haptable signals add`` says of ``--target PZ`` (it exits 2)."""
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "console.cli.entry",
            "signals",
            "add",
            "foo",
            EXPR,
            "--target",
            "PZ",
        ],
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2, (proc.returncode, proc.stderr)
    return proc.stderr


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_save_refuses_a_target_that_names_no_channel_as_play_and_the_cli_do(plugins, size):
    cli = _cli_refusal()
    assert REFUSAL in cli, cli

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            pane, lines = await _pane(app, pilot)
            _fields(app, EXPR, "mysig", "PZ")
            await pilot.press("ctrl+o")
            await wait_for(pilot, lambda: any("PZ" in x for x in lines), 20, "play refused")
            assert lines[-1] == REFUSAL, lines
            lines.clear()
            await pilot.press("ctrl+s")
            await wait_for(pilot, lambda: bool(lines), 10, "save answered")
            assert lines == [REFUSAL], lines
            assert "mysig" not in read_library(library_path("sim")).entries
            # a target that names a channel saves, and says which
            _fields(app, EXPR, "mysig", "pc")
            await pilot.press("ctrl+s")
            await wait_for(pilot, lambda: any("saved" in x for x in lines), 10, "saved")
            assert any(x.startswith("saved mysig for PC in ") for x in lines), lines
            assert read_library(library_path("sim")).entries["mysig"].target == "PC"

    asyncio.run(scenario())
