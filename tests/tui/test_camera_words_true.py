"""A new operator's try (issue 27, newuser7 #10): ``vision skipped 1 frames``; ``R:
body_threshold back as the profile has them``; the log said ``calibration saved
stopped: <path>`` while the screen's one-line result said only ``saved (k: again)``.
A count names one thing in the singular (``counted``); the log reads ``calibration
saved: <path>`` and the screen names the path as the screens show paths."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.session.events import Stopped
from console.tui.app import HapTableApp
from console.tui.camera_live import loop_lines
from console.tui.session_log import event_line

from .conftest import wait_for
from .test_camera_field_in_view import SAVED
from .test_camera_layout import _first_frame, text_in

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


def test_one_frame_is_one_frame():
    one = loop_lines({"latency": {"dropped_camera": 1, "dropped_queue": 1}}, "camera", 3.0)
    assert "camera lost 1 frame" in one and "vision skipped 1 frame (busy)" in one, one
    two = loop_lines({"latency": {"dropped_camera": 2, "dropped_queue": 0}}, "camera", 3.0)
    assert "camera lost 2 frames" in two and "vision skipped 0 frames (busy)" in two, two


def test_a_saved_calibration_is_logged_as_saved():
    line = event_line(Stopped("calibration", reason="saved: /tmp/x/touch_calibration.json"))
    assert line == ("calibration saved: /tmp/x/touch_calibration.json", "information")


@SIZES
def test_r_and_the_short_result_say_what_is_true(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            status = app.query_one("#camera-status")
            await pilot.press("t")
            await pilot.press("R")
            await wait_for(pilot, lambda: "R:" in text_in(app, status), 10, "R's line")
            assert "R: body_threshold back as the profile has it" in text_in(app, status)
            wiz = app.session.calibration
            wiz.result, wiz.message, wiz.failed = object(), SAVED, False
            short = " ".join(pane.short_result().replace("\n", "").split())
            path = SAVED.rsplit("saved to ", 1)[1]
            assert "saved to" in short and path.rsplit("/", 1)[1] in short, short

    asyncio.run(scenario())
