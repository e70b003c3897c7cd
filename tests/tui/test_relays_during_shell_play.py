"""Relays (F4) while ``haptable play sweep`` runs in a shell (issue 27, "visible and
truthful"): at 80 columns a routed row showed ``closed by haptable play sweep (pid N) -
yours:`` and the operator's setting was cut off without an ellipsis (wrapped, ``open``
alone under it once the pane scrolls); pressing 3 while the sweep played left its bracket
``[off]`` until the sweep ended although the setting is the operator's (the row says it
waits). Pilot at 80x24 and 120x40, the sweep a subprocess."""

from __future__ import annotations

import asyncio
import contextlib
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from textual.widgets import Switch

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines, text_in

ROOT = Path(__file__).resolve().parents[2]


def _seen(app, ch: int) -> str:
    """What the screen shows of relay ``ch``'s row (its visible part only)."""
    return text_in(app, app.query_one(f"#interlock-{ch}"))


def _lines(app, ch: int) -> list[str]:
    """The screen's lines inside relay ``ch``'s row, spaces collapsed."""
    r = app.query_one(f"#interlock-{ch}").region
    rows = screen_lines(app)[r.y : r.bottom]
    return [" ".join(row[r.x : r.right].split()) for row in rows]


def _on(app, ch: int) -> bool:
    return app.query_one(f"#relay-{ch}", Switch).value


def _sweep(*extra: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen(
        [sys.executable, "-m", "console.cli.entry", "play", "sweep", *extra],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


@contextlib.asynccontextmanager
async def _sweeping(app, pilot):
    """F4 from the first screen, four switches logged (the pane scrolls at 80x24), then
    ``haptable play sweep`` in a shell until it routes relay 2."""
    await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
    await pilot.press("f4")
    log = app.session.outputs.relay_log
    for n, key in enumerate("5566", 1):
        await pilot.press(key)
        await wait_for(pilot, lambda n=n: len(log()) == n, 10, f"switch {n}")
    proc = _sweep()
    try:
        await wait_for(pilot, lambda: "closed by" in _seen(app, 2), 20, "the sweep routes")
        yield proc
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_routed_rows_show_who_closed_it_and_your_setting_whole(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins))
        async with app.run_test(size=size) as pilot, _sweeping(app, pilot):
            await pilot.pause(0.3)
            for ch in (2, 3, 4):
                lines = _lines(app, ch)
                pid = re.search(r"pid \d+\)", " ".join(lines))
                assert pid, lines
                # each whole on one line: never "yours:" with "open" under it
                assert any("haptable play sweep (" + pid[0] in ln for ln in lines), lines
                assert any("yours: open" in ln for ln in lines), lines
                row = app.query_one(f"#interlock-{ch}")
                assert row.region.right <= app.screen.region.right, row.region

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_a_toggle_during_the_sweep_sets_the_bracket_at_once(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins))
        async with app.run_test(size=size) as pilot, _sweeping(app, pilot) as proc:
            await pilot.press("3")
            await pilot.pause(0.2)
            # the operator's setting at once; the row says the switch waits
            assert _on(app, 3), _seen(app, 3)
            assert "waits" in _seen(app, 3) and "sweep" in _seen(app, 3), _seen(app, 3)
            await pilot.pause(0.5)
            assert _on(app, 3), _seen(app, 3)  # no status read takes it back
            await asyncio.to_thread(proc.wait, 30)
            await wait_for(pilot, lambda: _seen(app, 3).startswith("closed"), 10, "closed")
            assert _on(app, 3)
            await wait_for(pilot, lambda: _seen(app, 2).startswith("open"), 10, "2 open")
            assert not _on(app, 2)

    asyncio.run(scenario())
