"""Issue 27, fourth new-user try: a TUIO target refused on the Camera screen (U) says
what is wrong with it (the address's number, the port's range), on one line."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera import _first_frame


def test_a_bad_tuio_target_says_what_is_wrong_with_it(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("U")
            box = app.query_one("#camera-target")
            await wait_for(pilot, lambda: box.has_focus, 10, "target field")
            box.value = "256.1.1.1:99999"
            await pilot.press("enter")
            said = lambda: words_on(app, "#camera-status")  # noqa: E731
            await wait_for(pilot, lambda: "256.1.1.1" in said(), 10, "refused")
            assert "256 is not 0-255 in an IPv4 address" in said(), said()
            assert "port 99999 is not 1-65535" in said(), said()
            assert app.session.camera_started.sink_state("tuio")[1] == "127.0.0.1:3333"

    asyncio.run(scenario())
