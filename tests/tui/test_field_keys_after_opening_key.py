"""A new-user trial: ``o/tmp/x`` sent in one burst (tmux send-keys) on Camera opened an
empty field while ``e`` started the exposure assistant, ``u`` turned TUIO on and ``t``
lowered a threshold; on Scope ``p`` froze the trace; ``U1.2.3.4:5`` was dropped the same
way. The keys typed after a key that opens a field go to that field, in order."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera import _first_frame


def burst(app, typed: str) -> None:
    """The keys of ``typed`` posted in one go, as a terminal delivers one write
    (pilot.press waits for the app to be idle after each key: none queue behind it)."""
    from textual import events
    from textual.keys import _character_to_key

    for char in typed:
        app.post_message(events.Key(_character_to_key(char), char))


SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


@SIZES
@pytest.mark.parametrize(
    ("screen", "field"), [("scope", "#scope-recording"), ("camera", "#camera-recording")]
)
def test_a_path_typed_behind_o_goes_to_the_field(plugins, size, screen, field):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial=screen)
        async with app.run_test(size=size) as pilot:
            if screen == "camera":
                await _first_frame(app, pilot)
                svc = app.session.camera_started
                params = svc.params()
            else:
                await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            burst(app, "o/tmp/eutx")
            box = app.query_one(field)
            await wait_for(pilot, lambda: box.value.endswith("/tmp/eutx"), 10, "the path typed")
            await pilot.pause(0.3)
            assert box.has_focus
            if screen == "camera":
                pane = app.query_one("CameraPane")
                assert pane._assisting is None, "e started the exposure assistant"
                assert not svc.sink_state("tuio")[0], "u turned TUIO on"
                assert svc.params() == params, "t changed a threshold"
            else:
                assert app.query_one("ScopePane").frozen is None, "p froze the Scope"

    asyncio.run(scenario())


@SIZES
def test_a_target_typed_behind_capital_u_goes_to_the_field(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            burst(app, "U1.2.3.4:5")
            box = app.query_one("#camera-target")  # it opens on the target in use, selected:
            typed = lambda: box.value == "1.2.3.4:5"  # noqa: E731 - the keys replace it
            await wait_for(pilot, typed, 10, "the keys typed behind U in the field")
            assert box.has_focus

    asyncio.run(scenario())
