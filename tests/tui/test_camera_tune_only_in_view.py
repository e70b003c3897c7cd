"""A new operator's try (issue 27, newuser7 #8): Camera (F2) at 80 x 24, ``k``'s result
shown (``... S: save``): the settings list with ``▸ body_threshold`` was off screen, and
``+`` still changed the hidden setting (14 to 16). A tuning key changes only a setting
whose row is in view: else it shows the row and says that the key again changes it."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import RESULT, _first_frame, text_in

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


@SIZES
def test_plus_changes_no_setting_out_of_view(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            pane, svc = app.pane("camera"), app.session.camera_started
            key = pane.chosen_key()
            settings, wizard = app.query_one("#camera-settings"), app.query_one("#camera-wizard")
            await pilot.press("k")
            await wait_for(pilot, lambda: "touch target" in text_in(app, wizard), 10, "wizard")
            await pilot.press("x")
            wiz = app.session.calibration
            wiz.result, wiz.message, wiz.failed = object(), RESULT, False
            await wait_for(pilot, lambda: "S: save" in text_in(app, wizard), 10, "the result")
            # a reply after it takes rows too (as the hand's lines did on the twin), and
            # the side panel scrolled back to its top (the mouse wheel): ▸ out of view
            pane.say("tuio: sending to 127.0.0.1:3333 as it did before the calibration ran")
            await pilot.pause(0.5)
            app.query_one("#camera-scroll").scroll_home(animate=False, immediate=True)
            await pilot.pause(0.1)
            before = svc.params()[key]
            shown = f"▸ {key}" in text_in(app, settings)
            assert not shown or size[1] > 24, text_in(app, settings)
            await pilot.press("plus")
            status = app.query_one("#camera-status")
            if not shown:  # not changed out of view: shown now, the line says so
                await wait_for(pilot, lambda: "again" in text_in(app, status), 10, "the line")
                assert svc.params()[key] == before, "changed while its row was hidden"
                assert key in text_in(app, status), text_in(app, status)
                await wait_for(
                    pilot, lambda: f"▸ {key}" in text_in(app, settings), 10, "the row shown"
                )
                await pilot.press("plus")
            await wait_for(pilot, lambda: svc.params()[key] > before, 10, "changed")
            await wait_for(pilot, lambda: f"▸ {key}" in text_in(app, settings), 10, "▸ in view")
            assert "S: save" in text_in(app, wizard), "the result gave way"

    asyncio.run(scenario())
