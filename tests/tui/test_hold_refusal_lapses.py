"""A screen's refusal because a shell's run holds the outputs leaves its line when the
hold ends (issue 27, "visible and truthful"): after ``haptable signals play long8`` from a
shell, F8 ctrl+o said ``refused: haptable signals play long8 (pid N) holds the outputs``
and the line stayed for minutes after the play ended, naming a dead pid (so after a shell
``haptable study run --simulate``). Relays' line goes when the hold ends; every screen's
hold refusal follows that check (``console.tui.lapse.lapse_if_held``). Pilot at 80x24
and 120x40."""

from __future__ import annotations

import asyncio
import os
import subprocess
import sys
from pathlib import Path

import pytest
from textual.widgets import Static

from console.cli.main import Context
from console.config.signal_library import add_signal, library_path
from console.tui.app import HapTableApp
from console.tui.lapse import HELD_ENDED

from .conftest import wait_for
from .test_signals_truthful_lines import _pane

ROOT = Path(__file__).resolve().parents[2]
SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
LONG = "sine(250 Hz, 5 V, 6 s) * ramp(20 ms)"  # over 5 s: the shell's play holds the table


def _shell(*argv: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "console.cli.entry", *argv],
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )


async def _ended(proc: subprocess.Popen) -> None:
    try:
        await asyncio.to_thread(proc.wait, 60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)


@SIZES
def test_signals_refusal_goes_when_the_shell_play_ends(plugins, size):
    add_signal(library_path("sim"), "long6", LONG, target="PA")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="signals")
        async with app.run_test(size=size) as pilot:
            pane, lines = await _pane(app, pilot)
            proc = _shell("signals", "play", "long6")
            try:
                await wait_for(
                    pilot, lambda: app.session.held_why() or proc.poll() is not None, 30, "held"
                )
                assert proc.poll() is None, proc.stderr.read()
                await pilot.press("ctrl+o")
                await wait_for(pilot, lambda: any("holds" in x for x in lines), 10, "refused")
                said = next(x for x in lines if "holds" in x)
                assert f"pid {proc.pid}" in said, said
            finally:
                await _ended(proc)
            assert proc.returncode == 0, proc.stderr.read()
            line = app.query_one("#sig-status", Static)
            await wait_for(pilot, lambda: pane._status_line == HELD_ENDED, 10, "lapsed")
            assert f"pid {proc.pid}" not in str(line.render())
            assert not line.has_class("error")

    asyncio.run(scenario())


@SIZES
def test_scenes_refused_demo_start_goes_when_the_shell_play_ends(plugins, size):
    add_signal(library_path("sim"), "long6", LONG, target="PA")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: app.pane("scenes") is not None, 10, "scenes")
            work = app.query_one("#demo-work")
            proc = _shell("signals", "play", "long6")
            try:
                await wait_for(
                    pilot, lambda: app.session.held_why() or proc.poll() is not None, 30, "held"
                )
                assert proc.poll() is None, proc.stderr.read()
                await pilot.press("d")
                table = app.query_one("#demo-table")
                await wait_for(pilot, lambda: app.focused is table, 10, "demo table")
                await pilot.press("enter")
                await wait_for(pilot, lambda: "holds the outputs" in work.text, 10, "refused")
                assert f"pid {proc.pid}" in work.text, work.text
            finally:
                await _ended(proc)
            assert proc.returncode == 0, proc.stderr.read()
            await wait_for(pilot, lambda: work.text == HELD_ENDED, 10, "lapsed")

    asyncio.run(scenario())
