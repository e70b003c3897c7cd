"""Devices (F1) on entry, at 80 x 24 and 120 x 40: the device table from its top (its
header and first row) and the sound card in use with the sound-card list's header, all
in view together, the screen not scrolled (a new operator's try at 80 x 24: the device
table began mid-row, its header and the audio row scrolled away); a row whose why is
cut to fit says it whole on Enter, as every cut cell does."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import DataTable

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import screen_lines


def _has(app, *words: str) -> bool:
    return any(all(w in line for w in words) for line in screen_lines(app))


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_devices_opens_on_the_top_and_the_card_in_use(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=size) as pilot:
            audio = app.query_one("#audio-table", DataTable)
            doctor = app.query_one("#device-table", DataTable)
            await wait_for(pilot, lambda: audio.row_count >= 2, 30, "sound cards listed")
            await wait_for(pilot, lambda: doctor.row_count >= 7, 30, "the devices checked")
            await wait_for(pilot, lambda: _has(app, "●", "twin", "digital twin"), 10, "in use")
            await pilot.pause(0.5)  # laid out
            assert app.focused is audio
            assert _has(app, "device", "driver", "state", "why"), screen_lines(app)
            assert _has(app, " audio ", "twin", "simulated"), screen_lines(app)
            assert _has(app, "driver", "device", "host API"), screen_lines(app)
            assert _has(app, "●", "twin", "digital twin"), screen_lines(app)
            assert app.pane("devices").scroll_y == 0
            # a row cut to fit: Enter on it says it whole
            doctor.focus()
            await pilot.press("home")
            await pilot.press("enter")
            said = " ".join(str(app.query_one("#devices-result").render()).split())
            assert "digital twin, 2 channels: piezo, screen" in said, said

    asyncio.run(scenario())
