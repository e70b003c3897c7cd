"""The Camera screen (F2) keeps the field being typed in and its reply in view, at
80 x 24 and 120 x 40, whatever the side panel holds above them: after a calibration's
result and a kept-settings line, ``o``'s recording field shows whole with its label and
example, and the reply to a path that is not there shows whole, under the field kept
open as typed; the result gives way."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import SIZES, _first_frame, assert_in_view, screen_lines, text_in

#: a finished calibration saved, as the session's wizard reports it (a long path)
SAVED = (
    "12 targets: reprojection error 0.00 mm rms, 0.00 mm max (leave-one-out 3.24 mm); "
    "outliers none. saved to /tmp/pytest-of-someone/pytest-391/pinned0/test-d2z24s1l/"
    "haptable_state_dir/sim/touch_calibration.json"
)


def _shows(app, widget) -> bool:
    try:
        assert_in_view(app, widget, str(widget))
    except AssertionError:
        return False
    return True


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_recording_field_and_its_reply_show_under_a_calibration_result(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            wiz = app.session.calibration
            wiz.result, wiz.message, wiz.failed = object(), SAVED, False
            wizard = app.query_one("#camera-wizard")
            await wait_for(pilot, lambda: "saved to" in text_in(app, wizard), 10, "result")
            await pilot.press(
                "W", "W"
            )  # (the first asks) its line names the overrides file (a long path)
            status = app.query_one("#camera-status")
            await wait_for(pilot, lambda: "kept in" in text_in(app, status), 10, "W's line")
            await pilot.press("o")
            box = app.query_one("#camera-recording", Input)
            await wait_for(pilot, lambda: app.focused is box, 10, "the field focused")
            await wait_for(pilot, lambda: _shows(app, box), 10, "the field in view")
            shown = "\n".join(screen_lines(app))
            assert "recording: a .h5 file's path" in shown, shown  # its label whole
            # the example, whole, on the status line above the field
            await wait_for(pilot, lambda: _shows(app, status), 10, "the example in view")
            assert text_in(app, status).endswith("trial_0000.h5"), text_in(app, status)
            box.value = "/nonexist"
            await pilot.press("enter")
            await wait_for(pilot, lambda: "no such file" in text_in(app, status), 30, "reply")
            await wait_for(pilot, lambda: _shows(app, status), 10, "the reply whole")
            said = text_in(app, status)
            assert said.endswith("one per trial)"), said
            # the field stays open with the path as typed, both it and the reply in view
            assert app.focused is box and box.value == "/nonexist"
            await wait_for(pilot, lambda: _shows(app, box), 10, "the field still in view")
            # closed and opened again: the path as typed, in view, the reply's rows given back
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.focused is pane, 10, "closed")
            await pilot.press("o")
            await wait_for(pilot, lambda: _shows(app, box), 10, "the field in view again")
            assert box.value == "/nonexist"
            # what was wrong stays said while the path is fixed
            assert "no such file" in text_in(app, status), text_in(app, status)

    asyncio.run(scenario())
