"""A number field never drops what is typed, at 80 x 24 and 120 x 40: it is as wide as
the longest number its range allows plus the cursor's cell, keeps every character typed
(a field taking at most that many turned ``abc`` into ``ab`` and ``99999999999`` into
``999`` in Gestures' subjects and reps, without a word), and the refusal quotes all it
holds. Gestures' subjects and reps, Studies' age and hand sizes are such fields."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.plugin_api.tui import NumberField
from console.tui.app import HapTableApp
from console.tui.number_field import number_length

from ..studies.studies_pilot import studies_idle
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
        assert f.region.width >= f.longest + 1, (f.id, f.region)


async def _type(pilot, field: Input, text: str) -> None:
    field.focus()
    await pilot.pause()
    field.value = ""
    await pilot.press(*text)


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_gestures_numbers_keep_what_is_typed(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs open")
            app.push_screen(plugins.of("panel")["gestures"].factory(app))
            await wait_for(pilot, lambda: type(app.screen).__name__ == "GesturesPanel", 30, "panel")
            panel = app.screen
            await wait_for(pilot, lambda: bool(panel.query("#gp-files")), 30, "panel composed")
            work = panel.work
            for name, typed, says in (
                ("subjects", "abc", "from 1 to 50"),
                ("reps", "99999999999", "from 1 to 500"),
            ):
                field = panel.query_one(f"#gp-{name}", Input)
                await _type(pilot, field, typed)
                assert field.value == typed, (name, field.value)  # nothing dropped
                await pilot.press("enter")
                await pilot.press("s")
                await wait_for(pilot, lambda n=name: f"{n} '" in work.text, 30, "refused")
                quoted = work.text.split("'")[1]
                assert quoted == typed, (quoted, work.text)
                assert work.text.endswith(f"give a whole number {says}"), work.text
                await _type(pilot, field, "5")
            _all_whole(app, panel)

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_studies_age_keeps_what_is_typed(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            pane = await studies_idle(app, pilot)
            status = lambda: words_on(app, "#study-status")  # noqa: E731
            pane.query_one("#simulate").value = False  # a person's details are checked
            field = pane.query_one("#age", Input)
            await _type(pilot, field, "1234567")
            await wait_for(pilot, lambda: "age = '" in status(), 30, "refused")
            quoted = status().split("age = '")[1].split("'")[0]
            assert quoted == field.value == "1234567", (quoted, field.value)
            hand = pane.query_one("#hand_width_cm", Input)
            await _type(pilot, hand, "12.345678")
            assert hand.value == "12.345678" and "12.345678".endswith(_shown(app, hand))
            _all_whole(app, pane)

    asyncio.run(scenario())
