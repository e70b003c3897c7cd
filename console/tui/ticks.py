"""Check boxes and switches whose state reads in words, not in shades: ``[x]`` / ``[ ]``
before a check box's label, ``[on ]`` / ``[off]`` on a switch (a new operator read an
unticked "record trials" as on: Textual's ``▐X▌`` is drawn in both states, only its
colour changes, and a dim screen hides that). Every check box and switch the console
shows is one of these (``tests/tui/test_ticks.py`` checks the sources)."""

from __future__ import annotations

from textual.content import Content
from textual.widgets import Checkbox, Switch

__all__ = ["Tick", "OnOff", "tick_mark", "on_off_mark"]


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
    the success colour, both on the panel."""

    DEFAULT_CSS = """
    Tick > .toggle--button { color: $foreground; background: $panel; }
    Tick.-on > .toggle--button { color: $text-success; background: $panel; }
    """

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
