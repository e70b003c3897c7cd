"""Blocks of a panel that give way to what the operator acts on: a panel's field being
typed in and the reply to it (its status line) keep their rows whole; the blocks above
them that only inform (the live numbers, a calibration's result) take what is left, the
one that yields last first, and are cut at the panel's height rather than push the field
or the reply below it (Camera screen, 80 x 24: ``o``'s field under a calibration's
result)."""

from __future__ import annotations

from collections.abc import Iterable

from textual.content import Content
from textual.widget import Widget


def natural_rows(widget: Widget) -> int:
    """The rows ``widget`` takes unlimited: its content's at its width, and its padding."""
    width = widget.content_region.width
    parent = widget.parent if isinstance(widget.parent, Widget) else widget
    content = widget.get_content_height(parent.size, widget.app.size, width) if width else 0
    return content + widget.styles.gutter.height


def text_rows(markup: str, width: int) -> int:
    """The rows ``markup`` takes wrapped at ``width`` cells (0 before a layout)."""
    return len(Content.from_markup(markup).wrap(width)) if width > 0 and markup else 0


def outer_rows(widgets: Iterable[Widget | None]) -> int:
    """The rows the shown ones of ``widgets`` take now (their margins too)."""
    return sum(w.outer_size.height for w in widgets if w is not None and w.display)


def give_way(
    room: int, kept: int, yielding: Iterable[Widget], whole: Iterable[Widget] = ()
) -> bool:
    """Limit the shown ones of ``yielding`` (the first keeps its rows longest) to the
    ``room`` rows ``kept`` leaves; each has its natural height again when there is room.
    Those in ``whole`` (a sentence, not a list of lines) show whole or not at all.
    Whether a limit changed (the panel is laid out again)."""
    shown = [w for w in yielding if w.display]
    # a shown block keeps its padding's rows however far it is limited (a limit of 0
    # still shows them): those are taken first, then the text's rows in order
    left = room - kept - sum(w.styles.gutter.height for w in shown)
    changed = False
    whole = set(whole)
    for widget in shown:
        gutter = widget.styles.gutter.height
        rows = natural_rows(widget) - gutter
        take = max(0, min(rows, left))
        if widget in whole and take < rows:
            take = 0
        limit = None if take >= rows else take + gutter
        now = widget.styles.max_height
        if (now.value if now is not None else None) != limit:
            widget.styles.max_height = limit
            changed = True
        left -= take
    return changed
