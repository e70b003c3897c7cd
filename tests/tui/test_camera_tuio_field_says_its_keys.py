"""Camera's TUIO target field (``U``) says what it takes and its keys on its border, as the
recording field (``o``) does; a refusal said while it is open advises what works there
(``u`` typed in the field is a letter of the host: ``Esc, then u`` turns TUIO off)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera import _first_frame
from .test_camera_layout import text_in


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_tuio_field_is_labelled_and_its_refusal_advises_keys_that_work_there(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("U")
            box = app.query_one("#camera-target")
            await wait_for(pilot, lambda: box.has_focus, 10, "target field")
            await pilot.pause(0.2)
            shown = text_in(app, box)
            assert "TUIO target: host:port" in shown, shown
            assert "Enter sets" in shown and "Esc back" in shown, shown
            box.value = "bad.invalid:3333"
            await pilot.press("enter")
            said = lambda: words_on(app, "#camera-status")  # noqa: E731
            await wait_for(pilot, lambda: "bad.invalid" in said(), 10, "refused")
            assert "Esc, then u turns TUIO off" in said(), said()
            assert "U sets host:port" not in said(), said()
            assert box.has_focus  # where the advice is read: it works from here
            await pilot.press("escape")
            await pilot.press("u")  # what it advised: TUIO on, then off again
            await wait_for(pilot, lambda: "tuio on" in said(), 10, said())

    asyncio.run(scenario())
