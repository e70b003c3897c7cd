"""A field whose value is checked after Enter, in a worker: a recording's path (``o`` on
Camera and Scope) and the TUIO target (``U`` on Camera). Enter leaves the field open, with
the focus and the text as typed, while the value is checked; only a value taken closes it
(``taken``: the focus back on the screen's widget). A refused one keeps it open as typed
(``refused``), so the keys typed next correct it and never act as the screen's keys: a
refused recording path closed its field, and the space of the path typed again switched
Scope from FROZEN to LIVE, a ``p`` ran "last plan". Esc closes it as before."""

from __future__ import annotations

from textual.widget import Widget
from textual.widgets import Input

__all__ = ["refused", "taken"]


def taken(box: Input, owner: Widget) -> None:
    """``box``'s value was taken: the field closes, its focus (if it has it) going back
    to ``owner``, the screen's widget."""
    had = box.has_focus
    box.display = False
    if had:
        owner.focus()


def refused(box: Input, owner: Widget) -> None:
    """``box``'s value was refused: the field stays open with the text as typed (never
    emptied or replaced), and has the focus again if the focus is still on ``owner``'s
    screen elsewhere (its owner, another of its widgets). Closed meanwhile (Esc), it
    stays closed; with another screen showing, the focus comes back to the field when
    that screen shows again (the app keeps the control each screen was left on)."""
    if not box.display:
        return
    focused = box.screen.focused
    if focused is not None and focused is not box and owner in focused.ancestors_with_self:
        box.focus()
