"""Open dropdown menus (a ``Select``'s overlay) close when the screen changes: an open
menu left behind on a hidden screen was drawn nowhere but kept the focus when the screen
came back (the footer said ``esc Dismiss menu``, Down then Enter changed the test signal
unseen)."""

from __future__ import annotations

from textual.dom import DOMNode
from textual.widget import Widget
from textual.widgets import Select
from textual.widgets._select import SelectOverlay


def close_menus(root: DOMNode, focused: Widget | None) -> Widget | None:
    """Close every open ``Select`` under ``root``; returns the widget to come back to
    for ``focused`` (an open menu's ``Select`` rather than its overlay)."""
    for select in root.query(Select):
        if select.expanded:
            select.expanded = False
    if isinstance(focused, SelectOverlay) and isinstance(focused.parent, Select):
        return focused.parent
    return focused


def menu_above(focused: Widget | None, bar: Widget) -> None:
    """An open menu (``focused``: a ``Select``'s overlay) stays above ``bar``, the safety
    bar, and what is docked under it: Textual moves a menu that does not fit below its
    ``Select`` up inside the screen (``constrain: inside``), over the e-stop state and
    the footer (Devices' test signals at 80 x 24). Its bottom margin is the rows from the
    bar's top to the screen's end, so it is moved up inside the rest, at every layout
    (wherever the screen scrolls the ``Select`` meanwhile)."""
    if isinstance(focused, SelectOverlay) and isinstance(focused.parent, Select):
        below = focused.screen.size.height - bar.region.y
        focused.styles.margin = (0, 0, max(below, 0), 0)
