"""A refused value keeps its field open, focused and as typed (``console.tui.checked_field``):
a new operator's try typed `/etc/passwd` into Scope's recording field (F9, `o`); the
refusal closed the field, and the space of the path typed again switched FROZEN to LIVE,
a `p` ran "last plan". The same on Camera's recording field and its TUIO target (`U`).
Only a value taken closes the field; Esc still closes it."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera import _first_frame
from .test_recording_view import recording as recording  # the fixture

SIZES = [(80, 24), (120, 40)]
IDS = ["80x24", "120x40"]


async def _refused_then_typed(app, pilot, field: str, typed: str, said: str, why: str):
    """Open ``field`` (its key pressed before), type ``typed``, Enter: refused, saying
    ``why`` on ``said``; then a space and a ``p`` go into the field, not the screen."""
    box = app.query_one(field, Input)
    await wait_for(pilot, lambda: box.has_focus, 20, f"{field} focused")
    box.value = typed
    box.cursor_position = len(typed)
    await pilot.press("enter")
    await wait_for(pilot, lambda: why in words_on(app, said), 30, "the refusal")
    await pilot.pause(0.2)
    assert box.display and box.has_focus, (box.display, app.focused)
    assert box.value == typed, box.value
    await pilot.press("space", "p")
    assert box.value == typed + " p", box.value  # typed into the field
    return box


@pytest.mark.parametrize("size", SIZES, ids=IDS)
def test_scope_refused_path_keeps_the_field(plugins, recording, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scope")
        async with app.run_test(size=size) as pilot:
            scope = app.pane("scope")
            await wait_for(pilot, lambda: app.focused is scope, 20, "scope focused")
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("space")  # FROZEN
            await wait_for(pilot, lambda: scope.frozen is not None, 10, "frozen")
            await pilot.press("o")
            box = await _refused_then_typed(
                app, pilot, "#scope-recording", "/etc/passwd", "#scope-head", "passwd"
            )
            assert scope.frozen is not None and not scope.plan_view  # no screen key ran
            # corrected: the file opens, the field closes, the screen has its keys back
            box.value = str(recording)
            await pilot.press("enter")
            await wait_for(pilot, lambda: "plan 1/1" in words_on(app, "#scope-head"), 30)
            assert not box.display and app.focused is scope

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES, ids=IDS)
def test_camera_refused_path_and_target_keep_their_fields(plugins, recording, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            await wait_for(pilot, lambda: app.focused is pane, 20, "camera focused")
            view = pane.view
            await pilot.press("o")
            box = await _refused_then_typed(
                app,
                pilot,
                "#camera-recording",
                "/nonexistent dir/x y.h5",
                "#camera-status",
                "no such file",
            )
            assert pane.view == view and pane.replay is None
            await pilot.press("escape")  # Esc still closes it
            await wait_for(pilot, lambda: app.focused is pane, 10, "closed")
            assert not box.display
            # the TUIO target: refused, the field stays as typed; taken, it closes
            await pilot.press("U")
            target = await _refused_then_typed(
                app, pilot, "#camera-target", "256.1.1.1:99999", "#camera-status", "256.1.1.1"
            )
            assert "Esc keeps the one in use" in words_on(app, "#camera-status")
            target.value = "127.0.0.1:3334"
            await pilot.press("enter")
            await wait_for(pilot, lambda: not target.display, 10, "target taken")
            assert app.focused is pane
            assert app.session.camera_started.sink_state("tuio")[1] == "127.0.0.1:3334"

    asyncio.run(scenario())
