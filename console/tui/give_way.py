"""Blocks of a panel that give way to what the operator acts on: a panel's field being
typed in and the reply to it (its status line) keep their rows whole; the blocks above
them that only inform (the live numbers, a calibration's result) take what is left, the
one that yields last first, and are cut at the panel's height rather than push the field
or the reply below it (Camera screen, 80 x 24: ``o``'s field under a calibration's
result)."""

from __future__ import annotations

from collections.abc import Callable, Iterable

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
    room: int,
    kept: int,
    yielding: Iterable[Widget],
    whole: Iterable[Widget] = (),
    ends: Callable[[Widget, int], int] | None = None,
    spare: Callable[[Widget], int] = lambda _w: 0,
) -> bool:
    """Limit the shown ones of ``yielding`` (the first keeps its rows longest) to the
    ``room`` rows ``kept`` leaves; each has its natural height again when there is room.
    Those in ``whole`` (a sentence, not a list of lines) show whole or not at all;
    ``ends(widget, rows)``: the rows of those it limits where it may end (at most
    ``rows``: a wrapped line is not cut); ``spare(widget)``: its last rows that only keep
    its height (blank), given none until every other has its rows. Whether a limit
    changed (the panel is laid out again)."""
    left = room - kept
    changed = False
    whole = set(whole)
    shown = [w for w in yielding if w.display]
    natural = {w: natural_rows(w) for w in shown}
    blank = {w: min(spare(w), natural[w]) for w in shown}
    left -= sum(natural[w] - blank[w] for w in shown)  # the rows left for spare ones
    spared = {}
    for w in shown:
        spared[w] = max(0, min(blank[w], left))
        left -= spared[w]
    left = room - kept
    for widget in shown:
        rows = natural[widget]
        need = rows - blank[widget] + spared[widget]
        take = max(0, min(need, left))
        if widget in whole and take < rows:
            take = 0
        elif ends is not None and take < rows:
            take = ends(widget, take)
        limit = None if take >= rows else take  # a spare row given no room: cut
        now = widget.styles.max_height
        if (now.value if now is not None else None) != limit:
            widget.styles.max_height = limit
            changed = True
        changed |= _padded(widget, limit != 0)  # given no rows: its padding's neither
        left -= take
    return changed


def _padded(widget: Widget, padded: bool) -> bool:
    """``widget`` with its padding (from its CSS), or none while it is given no rows (a
    row of padding alone would still take one). Whether that changed."""
    inline = widget.styles.inline
    if padded == (not inline.has_rule("padding")):
        return False
    if padded:
        inline.clear_rule("padding")
        widget.refresh(layout=True)
    else:
        widget.styles.padding = 0
    return True
