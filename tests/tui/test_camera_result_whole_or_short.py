"""Camera (F2) at 80 x 24 and 120 x 40: a finished, saved calibration's result is shown
whole or, when newer replies take the side panel's rows, in one line (``touch
calibration: 12 targets, saved to ~/.../touch_calibration.json (k: again)``) or not at all, never cut mid-sentence (after ``u`` the
block ended ``none. saved to`` with no path; after ``o`` only its heading was left)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_field_in_view import SAVED
from .test_camera_layout import SIZES, _first_frame, text_in


def _whole_or_short(shown: str) -> bool:
    """Whole, in one line, or not shown at all (no room for even that line)."""
    return not shown or shown.endswith(("touch_calibration.json", "(k: again)"))


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_a_saved_result_is_whole_or_one_line_under_newer_replies(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            wiz = app.session.calibration
            wiz.result, wiz.message, wiz.failed = object(), SAVED, False
            block = app.query_one("#camera-wizard")
            await wait_for(pilot, lambda: "saved to" in text_in(app, block), 10, "result")
            assert _whole_or_short(text_in(app, block)), text_in(app, block)
            status = app.query_one("#camera-status")
            for keys, said in ((("u",), "tuio"), (("o",), "recording")):
                await pilot.press(*keys)
                await wait_for(pilot, lambda s=said: s in text_in(app, status).lower(), 10, said)
                await pilot.pause(0.3)  # laid out after the reply
                await wait_for(
                    pilot, lambda: _whole_or_short(text_in(app, block)), 10, f"after {keys}"
                )
                await pilot.press("escape")

    asyncio.run(scenario())
