"""Issue 27, finding 14: Camera (F2) ``P`` holds the twin's hand flat on the glass (palm
and fingers down: the twin's pose touches). The vision's contacts are fingertip blobs, so
a flat hand has none; the hand's line said "0 touching" beside "touching skin at 227 ...
the light allows touches". It now says the hand lies flat, with the skin the vision
measured touching ("flat, 8500 mm2 touching"), beside "contacts 0" (fingertips)."""

from __future__ import annotations

import asyncio
import re

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import _first_frame, text_in


def _side(app) -> str:
    return text_in(app, app.query_one("#camera-side"))


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_flat_held_hand_reads_as_touching(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("P")  # a flat hand held still on the twin's glass
            await wait_for(pilot, lambda: "flat," in _side(app), 30, "the flat hand")
            side = _side(app)
            assert re.search(r"fingers spread, flat, \d+ mm2 touching", side), side
            assert "0 touching" not in side, side
            svc = app.session.camera_started
            res = svc.snapshot()[1]["result"]
            assert res.hands and not res.hands[0].contacts  # fingertips: none apart
            assert res.readings()["touching mm2"] > 2000  # palm and fingers on the glass

    asyncio.run(scenario())
