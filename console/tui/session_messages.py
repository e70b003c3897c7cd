"""The console session's events as Textual messages.

The app subscribes to its ``ConsoleSession`` and posts one ``SessionMessage`` per event to
itself (thread-safe); it then notifies the operator of failures and hands a copy of the
message to every mounted screen, which handles it in ``on_session_message``. Screens never
call each other: they observe the session.
"""

from __future__ import annotations

from textual.message import Message

from console.session.events import SessionEvent


class SessionMessage(Message, bubble=False):
    """One event of the console session (``event.topic`` says what it concerns). It does
    not bubble: the app hands each screen its own copy."""

    def __init__(self, event: SessionEvent) -> None:
        super().__init__()
        self.event = event
