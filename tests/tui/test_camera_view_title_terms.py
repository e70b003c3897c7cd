"""Camera (F2): each view's title names its range in the view's own terms (a new
operator's try: the diff view said `grey -1 to 31`, as if the camera's pixels were
negative): the camera's grey levels; the diff a difference over the background in grey
levels (`diff -1..+31 grey levels over background`); the high-pass a detail over its blur;
the body view the pixels over the body threshold."""

from __future__ import annotations

import asyncio
import re

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.units import view_levels

from .conftest import wait_for
from .test_camera_layout import SIZES, _first_frame, screen_lines

TITLES = {
    "camera": r"grey \d+ to \d+",
    "diff": r"diff [-+]\d+\.\.[-+]\d+ grey levels over background",
    "highpass": r"high-pass [-+]\d+\.\.[-+]\d+ grey levels over its blur",
    "body": r"body: white over the body threshold",
}


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_each_views_title_says_its_range_in_its_terms(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            for view in ("camera", "diff", "highpass", "body"):
                assert pane.view == view
                found = lambda v=view: any(  # noqa: E731
                    re.search(TITLES[v], ln) for ln in screen_lines(app)
                )
                await wait_for(pilot, found, 20, f"the {view} view's title")
                if view != "camera":
                    assert not any(re.search(r"grey -?\d+ to", ln) for ln in screen_lines(app))
                await pilot.press("v")

    asyncio.run(scenario())


def test_view_levels_words():
    assert view_levels("diff", -1.2, 30.6) == "diff -1..+31 grey levels over background"
    assert view_levels("camera", 8, 81) == "grey 8 to 81"
    assert view_levels("highpass", -3, 0) == "high-pass -3..+0 grey levels over its blur"
