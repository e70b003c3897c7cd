"""The Camera screen (F2) at 80 x 24: the live rows (frames lost and skipped, the hand,
clipped pixels, image noise) stay in view while the status line and the calibration
wizard's result have something to say (README: "the live numbers at the side panel's
top, never scrolled away by a status line")."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import RESULT, _first_frame, assert_in_view, text_in

SIZE = (80, 24)
LIVE = ("camera lost", "vision skipped", "hand at", "clipped pixels", "image noise")


def _side(app) -> str:
    return text_in(app, app.query_one("#camera-side"))


def test_live_rows_stay_in_view_under_a_status_line_and_a_wizard_result(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=SIZE) as pilot:
            await _first_frame(app, pilot)
            svc = app.session.camera_started
            svc.camera.place("open_hand", (370.0, 220.0))  # a hand: its row shows
            await wait_for(pilot, lambda: "hand at" in _side(app), 30, "the hand's row")
            pane = app.pane("camera")
            # a finished calibration, as the session's wizard reports it, and a status
            # line said meanwhile (an e result is as long)
            wiz = app.session.calibration
            wiz.result, wiz.message, wiz.failed = object(), RESULT, False
            pane.say(
                "e: set exposure 0.42, gain 1 (touching skin at 231 of 255, the contacts "
                "kept); W keeps them for the profile"
            )
            wizard = app.query_one("#camera-wizard")
            await wait_for(pilot, lambda: RESULT in text_in(app, wizard), 10, "the result")
            await pilot.pause(1.0)  # a few redraws of the live numbers
            shown = _side(app)
            for row in LIVE:
                assert row in shown, f"{row!r} not in view: {shown}"
            assert "S: save" in text_in(app, wizard)  # the key it asks for, still in view
            assert_in_view(app, wizard, "the result")
            assert "e: set exposure" in text_in(app, app.query_one("#camera-status"))

    asyncio.run(scenario())
