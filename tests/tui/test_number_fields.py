"""A number field shows whole what its check reads, at 80 x 24 and 120 x 40: it takes at
most the characters of the longest number its range allows and is that wide plus the
cursor's cell (a new operator typed ``99999999`` in Gestures' reps, the field showed
``9999999`` and the refusal quoted ``'99999999'``); the refusal quotes what it holds.
Gestures' subjects and reps, Studies' age and hand sizes are such fields."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.plugin_api.tui import NumberField
from console.tui.app import HapTableApp
from console.tui.number_field import number_length

from .conftest import wait_for, words_on
from .test_camera_layout import SIZES, screen_lines


def test_the_longest_number_of_a_range():
    assert number_length(1, 500) == 3 and number_length(1, 50) == 2
    assert number_length(3, 30, whole=False) == len("30.25")


def _shown(app, field: Input) -> str:
    row = screen_lines(app)[field.region.y]
    return row[field.region.x : field.region.right].strip()


def _all_whole(app, root) -> None:
    """Every number field under ``root`` at least as wide as its longest text and the
    cursor's cell."""
    fields = list(root.query(NumberField))
    assert fields
    for f in fields:
        assert f.max_length and f.region.width >= f.max_length + 1, (f.id, f.region)


async def _type(pilot, field: Input, text: str) -> None:
    field.focus()
    await pilot.pause()
    field.value = ""
    await pilot.press(*text)


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_gestures_reps_shows_what_its_check_quotes(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            app.push_screen(plugins.of("panel")["gestures"].factory(app))
            await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel", 30, "panel")
            panel = app.screen
            await wait_for(pilot, lambda: bool(panel.query("#gp-files")), 30, "panel composed")
            field = panel.query_one("#gp-reps", Input)
            await _type(pilot, field, "99999999")
            await pilot.press("enter")
            await pilot.press("s")
            work = panel.work
            await wait_for(pilot, lambda: "reps '" in work.text, 30, "refused")
            quoted = work.text.split("'")[1]
            assert quoted == field.value == _shown(app, field), (quoted, field.value)
            assert work.text.endswith("give a whole number from 1 to 500"), work.text
            _all_whole(app, panel)

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_studies_age_shows_what_its_check_quotes(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane("studies") is not None, 30, "studies")
            pane = app.pane("studies")
            status = lambda: words_on(app, "#study-status")  # noqa: E731
            await wait_for(pilot, lambda: "no study running" in status(), 30, "idle")
            pane.query_one("#simulate").value = False  # a person's details are checked
            field = pane.query_one("#age", Input)
            await _type(pilot, field, "1234567")
            await wait_for(pilot, lambda: "age = '" in status(), 30, "refused")
            quoted = status().split("age = '")[1].split("'")[0]
            assert quoted == field.value == _shown(app, field), (quoted, field.value)
            await _type(pilot, pane.query_one("#hand_width_cm", Input), "12.345678")
            assert _shown(app, pane.query_one("#hand_width_cm", Input)) == "12.34"
            _all_whole(app, pane)

    asyncio.run(scenario())
