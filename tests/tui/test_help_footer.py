"""A new operator's try (Camera, 80 x 24, ``?``): the help showed the Camera screen's
footer under it (``- + change [ ] setting v view k calibrate ...``), keys that do
nothing there, and not Esc, which closes it. The help's footer shows its own keys."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp, HelpScreen

from .conftest import wait_for
from .test_camera import _first_frame


def _bottom_row(app) -> str:
    return app.screen._compositor.render_strips()[-1].text


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_help_footer_shows_its_own_keys(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("question_mark")
            await wait_for(pilot, lambda: isinstance(app.screen, HelpScreen), 10, "help")
            await pilot.pause(0.5)
            row = " ".join(_bottom_row(app).split())
            assert "esc close" in row, row
            assert "scroll" in row, row
            for camera_key in ("calibrate", "view", "setting"):
                assert camera_key not in row, row
            scroll = app.screen.query_one("#help-scroll")
            await pilot.press("pagedown")
            await wait_for(pilot, lambda: scroll.scroll_y > 0, 10, "PageDown scrolls")
            await pilot.press("escape")
            await wait_for(pilot, lambda: not isinstance(app.screen, HelpScreen), 10, "closed")

    asyncio.run(scenario())
