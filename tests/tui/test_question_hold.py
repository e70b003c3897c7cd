"""The rule behind every timed question (``console.tui.question_hold``, through
``console.tui.lapse``): the question holds its screen's status line until it lapses or
is answered; a line said meanwhile is in the log at once and shows when it lapses; a
screen whose status setter does not wait cannot ask one."""

from __future__ import annotations

import asyncio
import logging

import pytest
from textual.app import App, ComposeResult
from textual.containers import Vertical
from textual.widgets import Static

from console.tui.lapse import ask, lapse
from console.tui.question_hold import answered, waits_for_question

from .conftest import wait_for


class Pane(Vertical):
    def __init__(self) -> None:
        super().__init__()
        self.line = ""

    def compose(self) -> ComposeResult:
        yield Static("", id="line")

    @waits_for_question
    def say(self, text: str) -> None:
        self.line = text
        self.query_one("#line", Static).update(text)

    def say_plainly(self, text: str) -> None:
        self.line = text


class Console(App):
    def compose(self) -> ComposeResult:
        yield Pane()


def test_a_question_holds_its_line_until_it_lapses(caplog):
    caplog.set_level(logging.INFO, "haptable.console")

    async def scenario():
        app = Console()
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.query_one(Pane)
            ask(pane, lambda: pane.line, "k again within 1 s closes it", pane.say, 1.0, "open")
            pane.say("played flow 1->2")  # a play ending meanwhile
            pane.say("played flow 2->1")
            assert pane.line == "k again within 1 s closes it"
            assert "played flow 1->2 (shown once its question lapses)" in caplog.text
            await wait_for(pilot, lambda: pane.line != "k again within 1 s closes it", 5, "")
            assert pane.line == "played flow 2->1"  # the newest, in place of "open"

    asyncio.run(scenario())


def test_an_answer_frees_the_line_at_once():
    async def scenario():
        app = Console()
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.query_one(Pane)
            ask(pane, lambda: pane.line, "k again within 1 s closes it", pane.say, 1.0, "open")
            pane.say("played flow 1->2")
            answered(pane)  # k again
            pane.say("closing ...")
            assert pane.line == "closing ..."
            await pilot.pause(1.5)
            assert pane.line == "closing ..."  # the waiting line is dropped (in the log)

    asyncio.run(scenario())


def test_a_question_on_a_setter_that_does_not_wait_is_refused():
    async def scenario():
        app = Console()
        async with app.run_test(size=(80, 24)):
            pane = app.query_one(Pane)
            with pytest.raises(TypeError, match="waits_for_question"):
                lapse(pane, lambda: pane.line, "x again within 1 s", pane.say_plainly, 1.0)

    asyncio.run(scenario())


def test_a_line_written_over_its_question_past_its_hold_is_reported():
    """A setter that does not wait, writing the question's line directly, is a bug
    every test catches (``OVERWRITTEN``, checked after each test by the conftest)."""
    from console.tui.question_hold import OVERWRITTEN

    async def scenario():
        app = Console()
        async with app.run_test(size=(80, 24)) as pilot:
            pane = app.query_one(Pane)
            ask(pane, lambda: pane.line, "k again within 0.3 s closes it", pane.say, 0.3, "open")
            pane.say_plainly("played flow 1->2")  # past the hold
            await wait_for(pilot, lambda: bool(OVERWRITTEN), 5, "reported")
            assert OVERWRITTEN == [
                ("Pane", "k again within 0.3 s closes it", "played flow 1->2")
            ], OVERWRITTEN
            OVERWRITTEN.clear()  # reported: this test's own, on purpose

    asyncio.run(scenario())
