"""Gestures panel (Camera ``g``), issue 27: ``s`` with ``/etc`` as the dataset said
``/etc: folder is not a synthesized dataset``; the dataset set back to a good folder
updated the files block but the refusal stayed. A refusal about the fields' values goes
when they change, whichever check said it (the fields' own, or the work's)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import SIZES
from .test_gestures_refused_dataset import _panel, _type


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_a_dataset_refusal_goes_when_the_dataset_changes(plugins, tmp_path, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            panel = await _panel(app, pilot, plugins)
            work = panel.work
            await _type(pilot, panel, "gp-dataset", "/etc")
            await pilot.press("enter")
            await pilot.press("s")
            await wait_for(pilot, lambda: "not a synthesized" in work.text, 30, "refused")
            await _type(pilot, panel, "gp-dataset", str(tmp_path / "twin"))
            await pilot.press("enter")
            await wait_for(pilot, lambda: "/etc" not in work.text, 10, f"gone: {work.text}")

    asyncio.run(scenario())
