"""The pilot's key presses in these tests (``conftest._quick_key_presses``): a key is
handled by the focused widget before ``pilot.press`` returns, even when the app's queue
is busy and hands work on to the widget, as the console does with every session message
(``HapTableApp.on_session_message`` posts a copy to each pane)."""

from __future__ import annotations

import asyncio

from textual.app import App, ComposeResult
from textual.message import Message
from textual.widgets import Static


class Busy(Message):
    """Work the app handles before the key and hands on to the widget."""


class Handed(Message):
    """The widget's copy of it."""


class Counter(Static, can_focus=True):
    BINDINGS = [("T", "up", "up")]

    def __init__(self) -> None:
        super().__init__("0")
        self.count = 0

    def action_up(self) -> None:
        self.count += 1

    async def on_handed(self, message: Handed) -> None:
        await asyncio.sleep(0.01)  # slower than the app: its copies queue up here


class BusyApp(App):
    def compose(self) -> ComposeResult:
        yield Counter()

    def on_mount(self) -> None:
        self.query_one(Counter).focus()

    async def on_busy(self, message: Busy) -> None:
        await asyncio.sleep(0.005)  # 40 of them hold the app's queue for 0.2 s
        self.query_one(Counter).post_message(Handed())


def test_a_key_is_handled_before_press_returns_while_the_app_is_busy():
    async def scenario():
        app = BusyApp()
        async with app.run_test() as pilot:
            counter = app.query_one(Counter)
            for n in range(1, 4):
                for _ in range(40):
                    app.post_message(Busy())
                await pilot.press("T")
                assert counter.count == n

    asyncio.run(scenario())
