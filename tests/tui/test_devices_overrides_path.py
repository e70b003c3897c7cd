"""Devices (F1) says whether the profile has saved settings and, once another screen's
key wrote them, their file's path (Camera's help says "its path: Devices, F1"; the line
showed nothing until a new console started)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.config.profile import overrides_path
from console.tui.app import HapTableApp

from .conftest import wait_for


def _line(app) -> str:
    return " ".join(str(app.query_one("#profile-line").render()).split())


def test_the_profile_line_names_the_settings_file_before_and_after_a_save(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="devices")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: "no saved settings yet" in _line(app), 10, "none")
            await pilot.press("f2")
            await wait_for(pilot, lambda: app.pane("camera").service is not None, 20, "camera")
            await pilot.press("u")  # TUIO on, kept for the profile: the file is written
            # once the sender answered (it is tried first; slower on a loaded machine)
            await wait_for(pilot, overrides_path("sim").exists, 20, "the file written")
            await pilot.press("f1")
            await wait_for(pilot, lambda: "saved settings:" in _line(app), 10, "saved")
            assert "overrides.toml" in _line(app), _line(app)

    asyncio.run(scenario())
