"""A second new operator's try on Devices (fresh start, shift+Tab to the table): for a
second or two the rows read `simul`/`ated`, `vibrom`/`eter`, the device column narrower
on some rows than on others, and the fix cell `press s (full` with its bracket cut at
the screen's edge. The first columns had widths the table grew as rows came, the rows
drawn before keeping the narrower one; they are given now. Every frame painted from the
start is checked: whole words, one column start per column, the fix whole."""

from __future__ import annotations

import asyncio
import re

import pytest
from textual.widgets import DataTable

from console.runtime.context import Context
from console.runtime.selftest_last import note_last
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines

CUT = re.compile(r"\b(simul|ated|vibrom|eter)\b")


def _device_lines(lines: list[str]) -> list[str]:
    """The device table's lines as painted: from its header to the sound-card heading."""
    start = next((i for i, ln in enumerate(lines) if ln.lstrip().startswith("device ")), None)
    if start is None:
        return []
    end = next((i for i in range(start, len(lines)) if lines[i].startswith("sound card")), None)
    return lines[start : end or len(lines)]


def _faults(lines: list[str]) -> list[str]:
    rows = _device_lines(lines)
    faults = [f"cut word: {ln}" for ln in rows if CUT.search(ln)]
    starts = {ln.index(" twin ") for ln in rows if ln.startswith((" audio ", " relays "))}
    faults += [f"driver column at {sorted(starts)}"] if len(starts) > 1 else []
    selftest = [ln for ln in rows if ln.startswith(" selftest")]
    faults += [f"bracket cut: {ln}" for ln in selftest if "(full" in ln and "(full)" not in ln]
    return faults


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_device_table_reads_whole_from_its_first_frame(plugins, size):
    note_last("sim", "quick", "ok", "quick self-test ok: all paths healthy", "haptable doctor")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            table = app.query_one("#device-table", DataTable)
            await wait_for(pilot, lambda: table.row_count >= 7, 30, "the devices checked")
            await pilot.press("shift+tab")
            await wait_for(pilot, lambda: table.has_focus, 10, "the device table")
            seen: list[str] = []
            for _ in range(30):  # about 1.5 s of frames, whole rows
                seen += _faults(screen_lines(app))
                await pilot.pause(0.05)
            assert not seen, "\n".join(dict.fromkeys(seen))
            table.move_cursor(row=table.row_count - 1)  # at 80 x 24 below the others
            await pilot.pause(0.2)
            assert not _faults(screen_lines(app)), "\n".join(screen_lines(app))
            fix = [ln for ln in _device_lines(screen_lines(app)) if ln.startswith(" selftest")]
            assert fix and all("press s" in ln for ln in fix), fix

    asyncio.run(scenario())
