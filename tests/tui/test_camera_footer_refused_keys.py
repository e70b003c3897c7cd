"""Camera (F2) while a demo holds the camera (issue 27, "visible and truthful"): the
footer offered ``- + change  [ ] setting  v view  k calibrate`` as if they worked, and
each was refused on the status line naming the demo. The footer now shows which keys
work now: the refused ones dimmed (still there: a press says why, naming the demo), the
others as before; all of them again once the camera is back. 80x24 and 120x40."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets._footer import FooterKey

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import _first_frame, text_in

#: footer keys that need the camera (the demo has it) -> their description
NEEDS_CAMERA = {"- +": "change", "[ ]": "setting", "v": "view", "k": "calibrate"}


def _footer(app) -> dict[str, bool]:
    """The footer's keys shown, each with whether it is dimmed (refused now)."""
    return {k.key_display: k.has_class("-disabled") for k in app.screen.query(FooterKey)}


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_footer_dims_the_keys_a_demo_holding_the_camera_refuses(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            shown = _footer(app)
            for key in NEEDS_CAMERA:
                assert shown.get(key) is False, shown  # offered, working
            svc = app.session.camera_started
            await asyncio.to_thread(svc.release, "demo knob")  # as a demo takes it
            await wait_for(pilot, lambda: _footer(app).get("k") is True, 10, "k dimmed")
            shown = _footer(app)
            for key in NEEDS_CAMERA:
                assert shown.get(key) is True, shown  # shown, dimmed
            assert shown.get("^e") is False or shown.get("ctrl+e") is False, shown
            assert shown.get("?") is False, shown  # help works
            # a dimmed key still answers: why, naming the demo (not silence)
            status = app.query_one("#camera-status")
            for key, said in (("k", "k refused"), ("v", "v refused"), ("plus", "+ refused")):
                await pilot.press(key)
                await wait_for(pilot, lambda s=said: s in text_in(app, status), 10, said)
                assert "demo knob" in text_in(app, status)
            await asyncio.to_thread(svc.give_back)
            await wait_for(pilot, lambda: _footer(app).get("k") is False, 10, "k back")
            shown = _footer(app)
            for key in NEEDS_CAMERA:
                assert shown.get(key) is False, shown

    asyncio.run(scenario())
