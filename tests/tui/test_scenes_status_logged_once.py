"""A new operator's try (issue 27, newuser7 #5): the knob demo stopped with ``s`` was
logged at 07:12:49 and again at 07:23:59 when F6 showed Scenes again, so the log read
as if the demo stopped then; ``x`` on the running demo logged ``demo knob has started``
twice (information and warning) in the same ms. A status line is logged once, when it
changes: showing a screen again never logs its standing lines as new; one event is one
log entry at one level."""

from __future__ import annotations

import asyncio
import logging

import pytest

from console.cli.main import Context
from console.tui import said
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_demos import _start

SIZES = pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])


class _Kept(logging.Handler):
    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)

    def with_words(self, words: str) -> list[tuple[str, str]]:
        return [(r.levelname, r.getMessage()) for r in self.records if words in r.getMessage()]


@SIZES
def test_a_stopped_demo_is_logged_once_however_often_scenes_shows(plugins, size, monkeypatch):
    monkeypatch.setattr(said, "PROGRESS_S", 0.0)  # eleven minutes later, as in the report

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        kept = _Kept()
        logging.getLogger(said.LOGGER).addHandler(kept)
        try:
            async with app.run_test(size=size) as pilot:
                pane = await _start(app, pilot, "knob")
                await pilot.press("x")  # the demo runs: x has nothing to cancel
                await pilot.pause(0.2)
                await pilot.press("s")
                await wait_for(pilot, lambda: pane.demo_name is None, 30, "demo stopped")
                await pilot.pause(0.3)
                for key in ("f1", "f6", "question_mark", "escape", "f2", "f6"):
                    await pilot.press(key)
                    await pilot.pause(0.3)
        finally:
            logging.getLogger(said.LOGGER).removeHandler(kept)
        stopped = [m for m in kept.with_words("knob stopped by s") if m[1].startswith("status")]
        assert len(stopped) == 1, stopped
        started = kept.with_words("demo knob has started")
        assert len(started) == 1, started

    asyncio.run(scenario())
