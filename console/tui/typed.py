"""Typed work is never lost to a key: ctrl+z in a text field brings back what it held
before each change (a key replacing the selected line, ctrl+t, a loaded signal ...).

Textual's ``Input`` has no undo. The app hears each field's first ``Input.Changed``
(posted when it mounts) and from then on watches its value: every change, typed or set
by code, is recorded the moment it happens (no message to wait for), so ctrl+z pressed
right after a key undoes that key.
"""

from __future__ import annotations

import weakref

from textual.widgets import Input

__all__ = ["TypedHistory"]

#: changes kept per field
DEPTH = 100


class TypedHistory:
    """The values each text field held before its changes, newest last."""

    def __init__(self, app) -> None:
        self.app = app
        self._past: weakref.WeakKeyDictionary[Input, list[str]] = weakref.WeakKeyDictionary()
        self._undoing: weakref.WeakSet[Input] = weakref.WeakSet()

    def follow(self, field: Input) -> None:
        """Record ``field``'s changes from now on (once per field)."""
        if field in self._past:
            return
        self._past[field] = []

        def changed(old: str, new: str) -> None:
            if field in self._undoing or old == new:
                return
            past = self._past.setdefault(field, [])
            past.append(old)
            del past[:-DEPTH]

        self.app.watch(field, "value", changed, init=False)

    def undo(self, field) -> bool:
        """``field`` back to what it held before its last change; False when it is no
        followed text field or has nothing to undo."""
        past = self._past.get(field) if isinstance(field, Input) else None
        if not past:
            return False
        value = past.pop()
        self._undoing.add(field)
        try:
            field.value = value
        finally:
            self._undoing.discard(field)
        field.cursor_position = len(value)
        return True
