"""Issue 27 (a new-user try at 80 x 24): the Camera screen's TUIO target field (``U``)
types ``?`` as the README promises (while it types the footer promises no key): the help
does not open and the footer shows no ``? help``; away from the field ``?`` helps again."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera import _first_frame


def _footer(app) -> str:
    from console.tui.narrow import ConsoleFooter

    return " ".join(str(k.render()) for k in app.screen.query_one(ConsoleFooter).children)


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_tuio_target_field_types_a_question_mark(plugins, size):
    from console.tui.app import HelpScreen

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("U")
            box = app.query_one("#camera-target")
            await wait_for(pilot, lambda: box.has_focus, 10, "target field")
            box.value = "host"
            box.cursor_position = len(box.value)
            await pilot.pause(0.3)
            assert "help" not in _footer(app), _footer(app)
            await pilot.press("question_mark")
            await pilot.pause(0.3)
            assert not isinstance(app.screen, HelpScreen), "? opened the help from the field"
            assert box.value == "host?"
            await pilot.press("escape")
            await wait_for(pilot, lambda: not box.has_focus, 10, "field left")
            await wait_for(pilot, lambda: "help" in _footer(app), 10, "help promised again")
            await pilot.press("question_mark")
            await wait_for(pilot, lambda: isinstance(app.screen, HelpScreen), 10, "help")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
@pytest.mark.parametrize(
    ("screen", "field"), [("scope", "#scope-recording"), ("camera", "#camera-recording")]
)
def test_every_path_field_types_a_question_mark(plugins, size, screen, field):
    """A second new operator's try: the recording field (`o` on Scope and Camera) opened
    the help on `?` while the TUIO target typed it, so a path holding `?` could not be
    typed. Every field taking a path types every key, its footer promising no `? help`."""
    from console.tui.app import HelpScreen

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial=screen)
        async with app.run_test(size=size) as pilot:
            if screen == "camera":
                await _first_frame(app, pilot)
            else:
                await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("o")
            box = app.query_one(field)
            await wait_for(pilot, lambda: box.has_focus, 10, "recording field")
            await pilot.press("a", "question_mark", "b")
            await pilot.pause(0.3)
            assert not isinstance(app.screen, HelpScreen), "? opened the help from the field"
            assert box.value.endswith("a?b"), box.value
            assert "help" not in _footer(app), _footer(app)

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_vibration_command_line_types_a_question_mark(plugins, size):
    """A new operator's try: ``:`` then ``load /tmp/a?b`` on Vibration opened the help
    and the line kept ``load /tmp/a``; the line takes paths (``load F.npz``, ``import
    PA=F.uff``): it types every key, its footer promising no ``? help``."""
    from console.tui.app import HelpScreen

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await pilot.press("colon")
            box = app.query_one("#vib-cmd")
            await wait_for(pilot, lambda: box.has_focus, 10, "command line")
            await pilot.press(*"load /tmp/a", "question_mark", "b")
            await pilot.pause(0.3)
            assert not isinstance(app.screen, HelpScreen), "? opened the help from the line"
            assert box.value == "load /tmp/a?b", box.value
            assert "help" not in _footer(app), _footer(app)

    asyncio.run(scenario())
