"""A toast on the title row leaves the title's words whole: centered where it clears the
toast, else at the row's left, else cut after a whole word with ``…`` or gone (a new
operator read the header cut mid-word beside a toast), on the main screens and the log,
at 80 x 24 and 120 x 40; when the toast goes the title is whole again."""

from __future__ import annotations

import asyncio

import pytest
from textual.widgets._toast import Toast

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.logs import LogScreen

from .conftest import wait_for
from .test_screens import _ready

#: toasts of every length from a word to the whole row
TOASTS = [
    "ok",
    "relay 3 closed",
    "the projector restarted",
    "camera: twin frames at 60 fps again after the demo",
    "Devices: the card in use changed to the twin; its outputs reopened with 2 channels",
]


def _top(app) -> str:
    return app.screen._compositor.render_strips()[0].text


def _title_part(app) -> str:
    """The title row left of the toast (the whole row with none)."""
    toasts = [t for t in app.screen.query(Toast) if t.region]
    row = _top(app)
    return row[: toasts[-1].region.x] if toasts else row


def _whole_words_of(shown: str, title: str) -> None:
    """What ``shown`` keeps of ``title`` is whole words (``…`` where words went)."""
    kept = shown.replace("⭘", "").strip()
    if not kept:
        return
    words = title.split()
    cut = kept.endswith("…")
    got = kept.removesuffix("…").split()
    assert got == words[: len(got)], (kept, title)
    assert cut or got == words, (kept, title)


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_title_keeps_whole_words_beside_a_toast(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size, notifications=True) as pilot:
            await _ready(app, pilot)
            title = f"{app.title} — {app.sub_title}"
            assert title in _top(app)
            for text in TOASTS:
                app.notify(text, timeout=30)
                await wait_for(pilot, lambda t=text: t[:2] in _top(app), 5, "the toast")
                await pilot.pause(0.1)
                _whole_words_of(_title_part(app), title)
            app.clear_notifications()
            for toast in app.screen.query(Toast):
                toast._expire()
            await wait_for(pilot, lambda: title in _top(app), 5, "the title whole again")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_log_title_keeps_whole_words_beside_a_toast(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size, notifications=True) as pilot:
            await _ready(app, pilot)
            await pilot.press("ctrl+l")
            await wait_for(pilot, lambda: "HapTable log" in _top(app), 5, "the log")
            for text in TOASTS:
                app.notify(text + " " + "x" * (size[0] - 20 - len(text)), timeout=30)
                await pilot.pause(0.2)
                _whole_words_of(_title_part(app), "HapTable log")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_the_log_opened_under_a_toast_keeps_whole_words(plugins, size):
    """A toast up before ctrl+l: the log's title row is laid out beside it at once (it
    read ``Hap▌ e-stop reset…``)."""

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="relays")
        async with app.run_test(size=size, notifications=True) as pilot:
            await _ready(app, pilot)
            text = "e-stop reset: outputs may play again " + "x" * (size[0] - 50)
            app.notify(text, timeout=30)
            await wait_for(pilot, lambda: "e-stop reset" in _top(app), 5, "the toast")
            await pilot.press("ctrl+l")
            await wait_for(pilot, lambda: isinstance(app.screen, LogScreen), 5, "the log")
            await pilot.pause(0.3)
            _whole_words_of(_title_part(app), "HapTable log")

    asyncio.run(scenario())
