"""A TUIO target refused on the Camera screen (U) is said on the status line while the
field is there to correct it; Esc cancels the field and the target in use stays: the
refusal of the typed one leaves the line, which says the target kept (a new operator's
try: the refusal stayed, as if the target in use were wrong). The refused target stays
in its open field as typed (``console.tui.checked_field``)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera import _first_frame


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_esc_on_the_target_field_takes_its_refusal_away(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            said = lambda: words_on(app, "#camera-status")  # noqa: E731
            box = app.query_one("#camera-target")
            await pilot.press("U")
            await wait_for(pilot, lambda: box.has_focus, 10, "target field")
            box.value = "256.1.1.1:99999"
            await pilot.press("enter")
            await wait_for(pilot, lambda: "256.1.1.1" in said(), 10, "refused")
            # the field stays open with the typed target, to correct ...
            assert box.has_focus and box.value == "256.1.1.1:99999"
            await pilot.press("escape")  # ... or not: cancelled
            await wait_for(pilot, lambda: "256.1.1.1" not in said(), 10, "the refusal gone")
            assert "127.0.0.1:3333" in said(), said()  # the target in use, said
            assert "kept" in said(), said()
            await pilot.press("U")  # the next U shows the target in use
            await wait_for(pilot, lambda: box.has_focus, 10, "target field, third")
            assert box.value == "127.0.0.1:3333"

    asyncio.run(scenario())
