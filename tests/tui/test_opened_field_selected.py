"""A field a key opens holding a value opens with that value selected: what is typed
replaces it, as in a dialog's prefilled field (issue 27, fifth new-user try: Camera `U`
opened on `127.0.0.1:3333` with the cursor at its end, and `nosuchhost.invalid:99999`
typed was refused as `'127.0.0.1:3333nosuchhost.invalid:99999'`). Every field opened
through ``console.tui.field_open.show_field`` (`U`, and `o` on Camera and Scope, which
open on a refused path as typed). 80 x 24 and 120 x 40."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera import _first_frame
from .test_field_keys_after_opening_key import burst

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


async def _type(pilot, text: str) -> None:
    """``text`` typed a key at a time, as a person types it."""
    for char in text:
        await pilot.press(char)


@SIZES
def test_the_tuio_target_opens_selected_and_typing_replaces_it(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            await wait_for(pilot, lambda: app.focused is pane, 20, "camera focused")
            await pilot.press("U")
            box = app.query_one("#camera-target", Input)
            await wait_for(pilot, lambda: box.has_focus, 10, "target field")
            assert box.value == "127.0.0.1:3333"
            assert box.selected_text == "127.0.0.1:3333", box.selection
            await _type(pilot, "nosuchhost.invalid:99999")
            assert box.value == "nosuchhost.invalid:99999"
            await pilot.press("enter")
            said = lambda: words_on(app, "#camera-status")  # noqa: E731
            await wait_for(pilot, lambda: "nosuchhost" in said(), 30, "refused")
            assert "3333nosuchhost" not in said(), said()
            # typed in one write behind U: the same
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.focused is pane, 10, "field closed")
            burst(app, "U1.2.3.4:5")
            await wait_for(pilot, lambda: box.value == "1.2.3.4:5", 10, box.value)

    asyncio.run(scenario())


@SIZES
@pytest.mark.parametrize(
    ("screen", "field"), [("scope", "#scope-recording"), ("camera", "#camera-recording")]
)
def test_a_recording_field_opens_on_its_refused_path_selected(plugins, size, screen, field):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial=screen)
        async with app.run_test(size=size) as pilot:
            if screen == "camera":
                await _first_frame(app, pilot)
            pane = app.pane(screen)
            await wait_for(pilot, lambda: app.focused is pane, 20, f"{screen} focused")
            await pilot.press("o")
            box = app.query_one(field, Input)
            await wait_for(pilot, lambda: box.has_focus, 10, "path field")
            await _type(pilot, "/nonexistent/x.h5")
            await pilot.press("enter")
            await pilot.pause(0.5)
            assert box.value == "/nonexistent/x.h5" and box.has_focus  # refused, kept
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.focused is pane, 10, "field closed")
            await pilot.press("o")
            await wait_for(pilot, lambda: box.has_focus, 10, "path field again")
            if box.value:  # it opens on the refused path, selected
                assert box.selected_text == box.value, (box.value, box.selection)
            await _type(pilot, "/tmp/y.h5")
            assert box.value == "/tmp/y.h5", box.value

    asyncio.run(scenario())
