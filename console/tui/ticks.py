"""Check boxes and switches whose state reads in words, not in shades: ``[x]`` / ``[ ]``
before a check box's label, ``[on ]`` / ``[off]`` on a switch (a new operator read an
unticked "record trials" as on: Textual's ``▐X▌`` is drawn in both states, only its
colour changes, and a dim screen hides that). Every check box and switch the console
shows is one of these (``tests/tui/test_ticks.py`` checks the sources)."""

from __future__ import annotations

import time

from textual import events
from textual.content import Content
from textual.message import Message
from textual.widgets import Checkbox, Switch

__all__ = ["Tick", "OnOff", "tick_mark", "on_off_mark", "TYPING_S"]

#: a space this soon after a character typed at a check box is a word's space, not a tick
TYPING_S = 1.5


def tick_mark(value: bool) -> str:
    """A check box's state as characters: ``[x]`` ticked, ``[ ]`` not."""
    return "[x]" if value else "[ ]"


def on_off_mark(value: bool) -> str:
    """A switch's state as a word: ``[on ]`` or ``[off]`` (one width: the row stays put)."""
    return "[on ]" if value else "[off]"


class Tick(Checkbox):
    """A check box drawn ``[x] label`` / ``[ ] label`` (ticked in bold). Its mark reads
    in both states: Textual draws an unticked button in ``$panel-darken-2`` on
    ``$panel`` (black on dark navy, colour 16 on 17 in a 256-colour terminal: a new
    operator could not read ``[ ]``); here unticked is the label's own colour, ticked
    the success colour, both on the panel.

    A space typed within ``TYPING_S`` of a character typed at it is a word's space (the
    operator believes a text field has the focus: a name's space unticked "simulated")
    and leaves it as it is; it posts ``Tick.SpaceHeld`` for the screen to say where the
    focus is. A space on its own ticks as always."""

    DEFAULT_CSS = """
    Tick > .toggle--button { color: $foreground; background: $panel; }
    Tick.-on > .toggle--button { color: $text-success; background: $panel; }
    """

    class SpaceHeld(Message):
        """A space taken for a word's, not a tick: ``tick`` has the focus."""

        def __init__(self, tick: Tick) -> None:
            super().__init__()
            self.tick = tick

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._typed_at = -TYPING_S  # the last character typed at it (monotonic seconds)

    def on_key(self, event: events.Key) -> None:
        """Note characters typed here; hold a space that follows one soon after."""
        now = time.monotonic()
        if event.key == "space" and now - self._typed_at < TYPING_S:
            event.stop()
            event.prevent_default()
            self._typed_at = now  # the next word's space is held too
            self.post_message(self.SpaceHeld(self))
        elif event.is_printable and event.key != "space":
            self._typed_at = now

    @property
    def words(self) -> str:
        """The label as the operator reads it (``simulated``)."""
        return " ".join(str(self.label).split())

    @property
    def _button(self) -> Content:
        style = self.get_visual_style("toggle--button")
        mark = Content.styled(tick_mark(self.value), style)
        return mark.stylize("bold") if self.value else mark


class OnOff(Switch):
    """A switch drawn ``[on ]`` / ``[off]`` (on in bold), five columns."""

    DEFAULT_CSS = """
    OnOff { width: 5; }
    OnOff.-on { text-style: bold; color: $text-success; }
    """

    def render(self) -> Content:
        return Content(on_off_mark(self.value))
