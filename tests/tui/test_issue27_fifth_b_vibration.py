"""Issue 27 (fifth, b): the Vibration screen at 80 x 24 as a new operator met it: every
status is shown whole (it wraps, no word cut), x with nothing running says so, and the
help lists every key the screen has."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import command, wait_for, words_on
from .test_camera_layout import text_in
from .test_screens import _load_map, _ready


def _status(app) -> str:
    return words_on(app, "#vib-status")


def _shown(app) -> str:
    """The status as the screen shows it (its visible rows, words joined)."""
    return text_in(app, app.query_one("#vib-status"))


def test_every_status_is_shown_whole_at_80_columns(plugins, map_file):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
        async with app.run_test(size=(80, 24)) as pilot:
            await _ready(app, pilot)
            pane = app.pane("vibration")
            await pilot.press("x")  # nothing runs: said so
            await wait_for(pilot, lambda: "nothing to cancel" in _status(app), 10, "x")
            await _load_map(app, pilot, map_file)
            await wait_for(pilot, lambda: pane.session.tables_ready, 30, "tables")
            await wait_for(pilot, lambda: "ready" in _status(app), 30, "ready")
            await pilot.press("b")
            await wait_for(pilot, lambda: "already built" in _status(app), 10, "b")
            await pilot.pause(0.1)
            assert _shown(app) == _status(app), _shown(app)
            assert _status(app).endswith("(a new map builds its own)")
            await command(app, pilot, "51 52")
            await wait_for(pilot, lambda: "flow 51->52" in _status(app), 30, "flow")
            await wait_for(pilot, lambda: "played flow" in _status(app), 30, "played")
            await pilot.pause(0.1)
            assert _shown(app) == _status(app), _shown(app)
            await pilot.press("x")
            await wait_for(pilot, lambda: "nothing to cancel" in _status(app), 10, "x")
            await pilot.press("question_mark")
            await wait_for(pilot, lambda: app.screen.query("#help-text"), 10, "help")
            help_text = " ".join(str(app.screen.query_one("#help-text").render()).split())
            for said in ("arrows", "escape", "ctrl+u", "x: cancel what runs"):
                assert said in help_text, said
            assert "listed here" not in help_text

    asyncio.run(scenario())
