"""Camera (F2), a new user on the twin (80 x 24): the side panel said ``touching skin at
184 of 255`` next to ``skin 164 below touch level 180, over 0.5x of it: the light
allows touches`` and ``both in grey over the background``: two numbers for one skin,
"below the touch level" next to "allows touches". Now one line for the skin with each
number named (in the image, of 255: what ``e`` keeps below clipping; over the empty
table: what the thresholds see) and one sentence on what it means for touches."""

from __future__ import annotations

import asyncio
import re

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.camera_live import touch_relation

from .conftest import wait_for
from .test_camera_layout import _first_frame

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


def _app(plugins) -> HapTableApp:
    return HapTableApp(Context("sim", plugins), fast=True, initial="camera")


def _words(app, selector: str) -> str:
    return " ".join(str(app.query_one(selector).content).split())


def test_the_touch_sentence_says_what_each_number_is():
    ok = touch_relation(164, 180, 164 / 180, 3)
    assert ok.startswith("touches: bright enough to be seen"), ok
    assert "below" not in ok and "164" not in ok and "contact_level 180" in ok, ok
    dark = touch_relation(80, 180, 80 / 180, 3)
    assert dark.startswith("touches: too dark") and "e (exposure assistant)" in dark, dark


@SIZES
def test_the_skin_has_one_number_and_one_sentence_on_touches(plugins, size):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("P")  # the twin's flat hand held still on the glass
            measures = "#camera-measures"
            await wait_for(pilot, lambda: "touches:" in _words(app, measures), 30, "measured")
            text = _words(app, measures)
            # one skin: the image's grey (of 255, what e measures) and how much brighter
            # than the empty table, each said once, in one line; one sentence on touches
            assert len(re.findall(r"skin[^.:;]{0,6}\d", text)) == 1, text
            assert re.search(r"touching skin at \d+ of 255 in the image, \d+ over the empty", text)
            assert text.count("touches:") == 1 and "below touch level" not in text, text
            assert "both in grey" not in text, text
            await pilot.press("P")

    asyncio.run(scenario())
