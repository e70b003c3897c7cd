"""A notification too long for the title row is cut after a whole word and ends in
``…`` (Textual cut it mid-word), at 80 x 24 and 120 x 40, and again at a word when the
terminal's width changes; the log keeps it whole."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets._toast import Toast

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.logs import view_handler

from .conftest import wait_for
from .test_screens import _ready

LONG = (
    "runtime watchdog: frame loop stalled 261 ms in camera (limit [runtime] "
    "watchdog_ms = 250); outputs silenced, relays opened; the demo's process "
    "restarted the projector twice before the operator's reset arrived"
)


def _top(app) -> str:
    return app.screen._compositor.render_strips()[0].text


def _toast(app) -> str:
    """The title row's toast as drawn (its border and padding included)."""
    toasts = [t for t in app.screen.query(Toast) if t.region]
    if not toasts:
        return ""
    region = toasts[-1].region
    return _top(app)[region.x : region.right]


def _cut_at_a_word(shown: str, whole: str) -> None:
    """``shown`` is ``whole`` up to the end of a word, then ``…``."""
    text = shown.strip()
    assert text.endswith("…"), repr(text)
    kept = text[:-1].rstrip()
    start = whole.index(kept[:20])
    assert whole[start:].startswith(kept), (kept, whole)
    after = whole[start + len(kept) :]
    assert after[:1] == " ", f"cut mid-word: {kept!r} then {after[:10]!r}"


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_long_toast_is_cut_at_a_word_and_logged_whole(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size, notifications=True) as pilot:
            await _ready(app, pilot)
            app.notify(LONG, severity="warning", timeout=30)
            await wait_for(pilot, lambda: "runtime watchdog" in _toast(app), 10, "the toast")
            _cut_at_a_word(_toast(app).lstrip("▌ "), LONG)
            handler = view_handler()
            if handler is not None:  # the log has it whole
                assert any(" ".join(LONG.split()) in line for line in handler.lines)
            other = (120, 40) if size == (80, 24) else (80, 24)
            await pilot.resize_terminal(*other)
            await pilot.pause(0.3)
            await wait_for(pilot, lambda: "runtime watchdog" in _toast(app), 10, "the toast")
            _cut_at_a_word(_toast(app).lstrip("▌ "), LONG)

    asyncio.run(scenario())


def test_a_titled_toast_shows_its_message_on_the_one_row(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=(80, 24), notifications=True) as pilot:
            await _ready(app, pilot)
            app.notify("the dataset folder is empty", title="Gestures", timeout=30)
            await wait_for(pilot, lambda: "Gestures" in _toast(app), 10, "the toast")
            assert "Gestures: the dataset folder is empty" in _toast(app), _toast(app)

    asyncio.run(scenario())
