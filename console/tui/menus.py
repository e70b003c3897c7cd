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
