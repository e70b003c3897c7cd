"""The Camera screen (F2) keeps in view what the operator acts on, at 80 x 24 and 120 x 40:
the widget with the focus (the TUIO target field after ``U``), the calibration wizard
with its result and the key it asks for (``S: save``), the chosen setting (``▸``) after
any number of ``]``; notifications never cover the screen's controls; the half-block IR
view spreads the frame's grey levels over the display's range."""

from __future__ import annotations

import asyncio
import re

import numpy as np
import pytest
from textual.widget import Widget
from textual.widgets import Input
from textual.widgets._toast import Toast

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera import _first_frame as first_frame

SIZES = [(80, 24), (120, 40)]


def _app(plugins) -> HapTableApp:
    return HapTableApp(Context("sim", plugins), fast=True, initial="camera")


async def _first_frame(app, pilot) -> None:
    await first_frame(app, pilot)
    await wait_for(pilot, lambda: app.focused is app.pane("camera"), 10, "camera focused")


def screen_lines(app) -> list[str]:
    """What the terminal shows now, a line per row."""
    return [strip.text for strip in app.screen._compositor.render_strips()]


def text_in(app, widget: Widget) -> str:
    """The text the screen shows inside ``widget``'s region (its visible part only), the
    rows joined with spaces and white space collapsed."""
    r = widget.region.intersection(app.screen.region)
    for anc in widget.ancestors:  # a container shows only what lies inside it
        if isinstance(anc, Widget):
            r = r.intersection(anc.region)
    rows = screen_lines(app)[r.y : r.bottom]
    return re.sub(r"\s+", " ", " ".join(row[r.x : r.right] for row in rows)).strip()


def assert_in_view(app, widget: Widget, what: str) -> None:
    """``widget`` is laid out inside the screen, inside every container it scrolls in,
    and what the screen shows at its corners is the widget (or a child of it): nothing
    covers it."""
    region = widget.region
    assert region.area > 0, f"{what}: not laid out ({region})"
    assert app.screen.region.contains_region(region), f"{what}: {region} off the screen"
    for anc in widget.ancestors:
        if isinstance(anc, Widget) and anc is not app.screen:
            assert anc.region.contains_region(region), f"{what}: {region} outside {anc}"
    for x, y in (
        (region.x, region.y),
        (region.right - 1, region.y),
        (region.x, region.bottom - 1),
        (region.right - 1, region.bottom - 1),
    ):
        shown, _ = app.screen.get_widget_at(x, y)
        assert widget in shown.ancestors_with_self, f"{what}: {shown} covers ({x}, {y})"


def _focus_shows(app, after: str) -> bool:
    try:
        assert_focus_in_view(app, after)
    except AssertionError:
        return False
    return True


def assert_focus_in_view(app, after: str) -> None:
    focused = app.focused
    assert focused is not None, f"after {after}: no focus"
    assert_in_view(app, focused, f"the focus ({focused}) after {after}")


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_tuio_target_field_shows_when_it_takes_the_focus(plugins, size):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            assert_focus_in_view(app, "start")
            await pilot.press("U")
            await wait_for(pilot, lambda: isinstance(app.focused, Input), 10, "the field")
            await wait_for(pilot, lambda: _focus_shows(app, "U"), 15, "the field in view")
            await pilot.pause(1.0)  # and it stays there as the live numbers change (a hand
            # coming into view adds a row to the panel: the next tick scrolls it back)
            await wait_for(pilot, lambda: _focus_shows(app, "U"), 3, "the field still in view")
            assert_focus_in_view(app, "U")
            assert ":" in text_in(app, app.focused)  # host:port, readable
            await pilot.press("escape")
            await wait_for(pilot, lambda: app.focused is app.pane("camera"), 10, "back")
            assert_focus_in_view(app, "escape")
            for key in ("k", "x", "v", "b", "T", "minus", "u", "u", "U"):  # whatever the key
                await pilot.press(key)
                # within a few frames (a notification arriving takes rows: the side
                # panel scrolls again)
                await wait_for(pilot, lambda k=key: _focus_shows(app, k), 15, f"focus after {key}")

    asyncio.run(scenario())


RESULT = (
    "12 targets: reprojection error 1.23 mm rms, 3.45 mm max (leave-one-out 1.67 mm); "
    "outliers none. S: save"
)


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_calibration_wizard_and_its_result_are_in_view(plugins, size):
    """k starts the wizard: what to touch shows; its result (a finished run's report)
    shows whole with the key it asks for."""

    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            await pilot.press("k")
            assert pane.calibration is not None
            wizard = app.query_one("#camera-wizard")
            await wait_for(
                pilot, lambda: "touch target 1 of 12" in text_in(app, wizard), 10, "the wizard"
            )
            assert_in_view(app, wizard, "the wizard")
            assert "x" in text_in(app, wizard) and "cancel" in text_in(app, wizard)
            await pilot.press("x")
            # a finished run, as the session's wizard reports it
            wiz = app.session.calibration
            wiz.result, wiz.message, wiz.failed = object(), RESULT, False
            await wait_for(pilot, lambda: RESULT in text_in(app, wizard), 10, "the result")
            assert_in_view(app, wizard, "the result")
            assert_focus_in_view(app, "the result")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_chosen_setting_stays_in_view(plugins, size):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=size, notifications=True) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            n = len(app.session.camera_started.params())
            for i in range(n + 2):  # round the list and on
                await pilot.press("right_square_bracket")
                key = pane.chosen_key()
                await wait_for(
                    pilot,
                    lambda k=key: any(f"▸ {k} " in line for line in screen_lines(app)),
                    5,
                    f"▸ {key} on the screen after {i + 1} x ]",
                )
                line = next(ln for ln in screen_lines(app) if f"▸ {key} " in ln)
                y = screen_lines(app).index(line)
                x = line.index("▸")
                shown, _ = app.screen.get_widget_at(x, y)
                assert pane in shown.ancestors_with_self, (key, shown)  # not a toast's
                assert_focus_in_view(app, f"{i + 1} x ]")
            for _ in range(3):  # the other direction, and a change of the chosen one
                await pilot.press("left_square_bracket", "plus")
                key = pane.chosen_key()
                await wait_for(
                    pilot,
                    lambda k=key: any(f"▸ {k} " in line for line in screen_lines(app)),
                    5,
                    f"▸ {key} on the screen after [",
                )

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_notifications_leave_the_controls_uncovered(plugins, size):
    """Tuning, saving, switching TUIO: whatever the console notifies stands in its own
    rows above the safety bar; the screen's controls, the bar and the footer stay
    uncovered."""
    from textual.widgets import Footer

    from console.tui.safety_bar import SafetyBar

    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=size, notifications=True) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("right_square_bracket", "T", "plus", "W", "b", "u", "u")
            for _ in range(3):  # the screen's own outcomes are on its status line
                app.notify("a long message " * 8)
            # the newest only shows (``console.tui.toasts``)
            await wait_for(pilot, lambda: len(app.screen.query(Toast)) == 1, 10, "toasts")
            await pilot.pause(0.3)  # laid out
            covered = [app.query_one("#tabs"), app.query_one(SafetyBar), app.query_one(Footer)]
            toast_cells = [
                (x, y)
                for y in range(app.screen.size.height)
                for x in range(app.screen.size.width)
                if isinstance(app.screen.get_widget_at(x, y)[0], Toast)
            ]
            assert toast_cells  # they show
            for w in covered:
                on = [c for c in toast_cells if w.region.contains(*c)]
                assert not on, (w, w.region, on[:3])
            assert_focus_in_view(app, "the toasts")
            settings = app.query_one("#camera-settings")
            # the chosen row (bounded: a loaded machine lays the side panel out again
            # after the last status line, its settings empty for that frame)
            await wait_for(pilot, lambda: "▸" in text_in(app, settings), 10, "the ▸ row")

    asyncio.run(scenario())


def test_halfblock_view_spreads_a_dark_frame_over_the_grey_range(plugins):
    """The twin's frame is dark (most pixels well below 64): the view shows it with its
    grey levels stretched (the darkest few per cent black, the brightest white), the
    stretch following the frames slowly (no flicker from one frame to the next)."""

    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=(120, 40)) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            await wait_for(pilot, lambda: pane.shown is not None, 10, "a picture")
            await pilot.pause(1.0)
            grey = pane.shown.rgb[..., 0].astype(float)
            # shown as it comes, 90 % of the twin's frame lies within 8..55 of 255, its
            # median near 28: stretched, they spread over most of the range
            lo, mid, hi = np.percentile(grey, [5, 50, 95])
            assert hi - lo >= 100 and mid >= 48, (lo, mid, hi)
            assert ", grey " in str(app.query_one("#camera-title").render())  # the levels shown

    asyncio.run(scenario())


def test_display_stretch_is_steady_and_follows_slowly():
    from console.tui.halfblock_view import GreyStretch

    rng = np.random.default_rng(1)
    frame = rng.normal(30, 3, (48, 64))
    frame[10:20, 10:30] = 60  # a hand
    s = GreyStretch()
    first = s(frame)
    assert first.min() <= 10 and first.max() >= 245
    # the next frames' noise does not move the levels: the same scene shows the same
    for _ in range(10):
        again = s(frame + rng.normal(0, 0.5, frame.shape))
    assert np.abs(again - first).mean() < 8
    # a brighter scene: the levels follow over several frames, not at once
    bright = frame * 3
    step1 = s(bright)
    assert (step1 >= 254.9).mean() > 0.5  # mostly clipped at first
    for _ in range(60):
        last = s(bright)
    assert (last >= 254.9).mean() < 0.1  # only the hand at the top
    assert (last <= 0.1).mean() < 0.1
    # a flat frame is not noise blown up to the full range
    flat = s.__class__()(np.full((8, 8), 20.0) + rng.normal(0, 0.5, (8, 8)))
    assert np.ptp(flat) < 64
