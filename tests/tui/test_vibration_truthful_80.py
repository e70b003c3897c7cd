"""Issue 27, the Vibration screen as a new operator met it at 80 x 24: ``m`` during an
e-stop is refused in the console's words; the progress bar and its line side by side,
whole; the keys f and r named by the points they play; a point off the grid answered
with the grid's range; a later success replaces a failed command's error and its text."""

from __future__ import annotations

import asyncio
import threading

import pytest

from console.cli.main import Context
from console.session.vibration import Cancelled
from console.tui.app import HapTableApp
from console.tui.command_line import CommandLine

from .conftest import command, wait_for, words_on
from .test_camera_layout import screen_lines
from .test_screens import _load_map, _ready


def _status(app) -> str:
    return words_on(app, "#vib-status")


def _info(app) -> str:
    return words_on(app, "#vib-info")


def test_m_during_an_estop_is_refused_in_the_console_s_words(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            asked: list[int] = []
            real = app.session.vibration.measure
            app.session.vibration.measure = lambda *a, **kw: asked.append(1) or real(*a, **kw)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: app.session.outputs.estopped, 10, "e-stopped")
            await pilot.press("m")
            await wait_for(pilot, lambda: "refused" in _status(app), 10, "refusal")
            assert "measure refused: e-stop active, ctrl+r resets" in _status(app)
            assert not pane.query_one("#vib-progress").display
            await command(app, pilot, "measure")  # typed: refused too, the text kept
            line = app.query_one("#vib-cmd", CommandLine)  # kept open to be fixed
            await wait_for(pilot, lambda: app.focused is line, 10, "the line")
            assert "measure refused" in _status(app)
            assert app.query_one("#vib-cmd", CommandLine).value == "measure"
            await pilot.pause(0.3)
            assert asked == []
            await pilot.press("ctrl+r")  # the reset clears the refusal
            await wait_for(pilot, lambda: "refused" not in _status(app), 10, "cleared")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_progress_bar_and_its_line_do_not_overlap(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            release = threading.Event()

            def held(progress, cancelled):
                progress(0.5, "step 4/8")
                release.wait(30)
                raise Cancelled()

            app.session.vibration.measure = held
            await pilot.press("m")
            try:
                await wait_for(pilot, lambda: "step 4/8" in _status(app), 30, "progress")
                bar, label = pane.query_one("#vib-progress"), pane.query_one("#vib-status")
                await wait_for(pilot, lambda: "50%" in str(screen_lines(app)), 10, "50%")
                assert bar.region.right < label.region.x, (bar.region, label.region)
                row = screen_lines(app)[label.region.y]
                assert "50% " in row and "measuring: twin" not in row.split("50%")[0], row
            finally:
                release.set()
            await wait_for(pilot, lambda: "cancelled" in _status(app), 30, "ended")

    asyncio.run(scenario())


def test_f_and_r_are_named_by_the_points_they_play(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            await _load_map(app, pilot, map_file)
            footer = screen_lines(app)[-1]
            assert "1->2" not in footer and "2->1" not in footer, footer
            await command(app, pilot, "51")
            await wait_for(pilot, lambda: "played point 51" in _status(app), 30, "51")
            await command(app, pilot, "52")
            await wait_for(pilot, lambda: "played point 52" in _status(app), 30, "52")
            await wait_for(pilot, lambda: "f: flow 51 -> 52" in _info(app), 30, "hint")
            assert "r: flow 52 -> 51" in _info(app)
            await pilot.press("f")
            await wait_for(pilot, lambda: "played flow 51->52" in _status(app), 30, "f")
            await pilot.press("r")
            await wait_for(pilot, lambda: "played flow 52->51" in _status(app), 30, "r")

    asyncio.run(scenario())


def test_a_point_off_the_grid_names_the_grid_s_range(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            await command(app, pilot, "999")  # no map yet: the grid's range all the same
            await wait_for(pilot, lambda: "999" in _status(app), 10, "refused")
            assert "point 999: the grid has points 1-84" in _status(app)
            await _load_map(app, pilot, map_file)
            await command(app, pilot, "999")
            await wait_for(pilot, lambda: "point 999" in _status(app), 10, "refused")
            assert "point 999: the grid has points 1-84" in _status(app)
            await command(app, pilot, "51 999")
            await wait_for(pilot, lambda: "51" not in _status(app), 10, "refused")
            assert "point 999: the grid has points 1-84" in _status(app)
            assert app.session.played == []

    asyncio.run(scenario())


def test_m_asks_before_replacing_the_kept_map(plugins):
    """A single key never replaces the kept map silently (seventh new-user try): the first
    m says what a second one does; only m again measures."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            kept = app.session.vibration.cached_map_path()
            kept.parent.mkdir(parents=True, exist_ok=True)
            kept.write_bytes(b"")  # a kept map exists (its content is not read here)
            asked: list[int] = []
            app.session.vibration.measure = lambda *a, **kw: (
                asked.append(1) or (_ for _ in ()).throw(Cancelled())
            )
            await pilot.press("m")
            await pilot.pause(0.3)
            assert "m again within 5 s" in _status(app) and not asked
            await pilot.press("m")
            await wait_for(pilot, lambda: asked, what="the second m measures")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_every_word_that_is_no_point_is_named_on_the_line(plugins, map_file, size):
    """A second new operator's try: `:999 abc` named only 'abc'; `:load` of a path with
    a space did not say to quote it."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=size) as pilot:
            await _ready(app, pilot)
            await _load_map(app, pilot, map_file)
            await command(app, pilot, "999 abc")
            await wait_for(pilot, lambda: "abc" in _status(app), 10, "refused")
            assert "point 999 is off the grid" in _status(app), _status(app)
            assert "'abc' is no point id" in _status(app), _status(app)
            await command(app, pilot, "load /tmp/no such/x.npz")
            await wait_for(pilot, lambda: "quote" in _status(app), 10, "refused")
            assert app.session.played == []

    asyncio.run(scenario())
