"""Keys typed right after a screen switch go to the screen shown when they were typed.

An F-key (or the palette, or a click on a tab) switches the screen at once, but the new
screen's main widget takes the focus a refresh or two later (later still the first
time, while the pane is built). Under load the keys typed behind the F-key arrive in
that gap: with no widget of the new screen focused they reached no screen, or the old
one. While a switch waits for its focus, ``KeyHold`` keeps such keys (not the app's
priority keys: E-STOP, the screens, help act at once) and hands them on, in the order
typed, once the new screen has the focus (or the wait gave up)."""

from __future__ import annotations

from typing import Any

from textual import events


class KeyHold:
    """The keys held for the screen being switched to (``app._focus_wanted`` set)."""

    def __init__(self, app: Any) -> None:
        self.app = app
        self.held: list[events.Key] = []

    def _priority(self, key: str) -> bool:
        return any(b.priority for b in self.app._bindings.key_to_bindings.get(key, ()))

    def hold(self, event: events.Event) -> bool:
        """Whether ``event`` (a key, not forwarded) waits for the switch's focus."""
        if not isinstance(event, events.Key) or event.is_forwarded:
            return False
        app = self.app
        if app._focus_wanted is None and not self.held:
            return False
        if app.screen is not app.base or self._priority(event.key):
            return False  # a modal's keys, E-STOP, the screens: at once
        self.held.append(events.Key(event.key, event.character))
        return True

    def release(self) -> None:
        """The switch has its focus (or gave up): the held keys go on, in order."""
        held, self.held = self.held, []
        for key in held:
            self.app.post_message(key)
