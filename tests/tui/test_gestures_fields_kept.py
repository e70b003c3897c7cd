"""The Gestures panel (Camera F2, ``g``) keeps what was typed in its fields when it
closes (``Esc``, or an F-key while in a field) and shows it again when it opens (new
operator's try: subjects 2 and reps 2 were back to 5 and 40 after closing)."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_gestures_work_kept import _panel_from_camera


def _value(panel, name: str) -> str:
    return panel.query_one(f"#gp-{name}", Input).value


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_typed_fields_survive_closing_and_opening_the_panel(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            panel = await _panel_from_camera(app, pilot)
            await pilot.press("tab", "tab", "2", "tab", "2")  # subjects 2, reps 2
            assert (_value(panel, "subjects"), _value(panel, "reps")) == ("2", "2")
            await pilot.press("escape", "escape")  # the field, then the panel
            await wait_for(pilot, lambda: app.screen is app.base, 10, "panel closed")
            panel = await _panel_from_camera(app, pilot)
            assert (_value(panel, "subjects"), _value(panel, "reps")) == ("2", "2")
            # an F-key while in a field closes the panel: the field is kept too
            await pilot.press("tab", "tab", "tab", "3", "tab", *"loso")
            assert app.focused is panel.query_one("#gp-cv", Input)
            await pilot.press("f2")
            await wait_for(pilot, lambda: app.screen is app.base, 10, "panel closed")
            panel = await _panel_from_camera(app, pilot)
            assert (_value(panel, "subjects"), _value(panel, "reps")) == ("2", "3")
            assert _value(panel, "cv") == "loso"

    asyncio.run(scenario())
