"""A list's own keys in the footer: the focused list shows what Enter (and Delete) do
there first, before the screen's keys (Textual's ``OptionList`` hides its Enter and has
no Delete, so the footer of a focused list named none of them).

``KeyedList(keys={"enter": "load", "delete": "remove"}, on_delete=fn)`` is an
``OptionList`` whose Enter selects as before and whose Delete calls ``fn`` with the
highlighted entry's id (the screen decides what it does), each key shown in the footer
with its word while the list has the focus."""

from __future__ import annotations

from collections.abc import Callable

from textual.binding import Binding
from textual.widgets import OptionList

from console.tui.focus_keys import show_keys

#: the keys a list can show, with the action each runs
LIST_ACTIONS = {"enter": "select", "delete": "delete_pressed"}


class KeyedList(OptionList):
    """An ``OptionList`` whose own keys (``keys``: key -> word) show first in the footer."""

    BINDINGS = [Binding("delete", "delete_pressed", "delete", show=False)]

    def __init__(
        self,
        *options,
        keys: dict[str, str],
        on_delete: Callable[[str], None] | None = None,
        **kw,
    ) -> None:
        super().__init__(*options, **kw)
        unknown = set(keys) - set(LIST_ACTIONS)
        if unknown or ("delete" in keys and on_delete is None):
            raise ValueError(f"KeyedList keys {sorted(keys)}: use {sorted(LIST_ACTIONS)}")
        self.on_delete = on_delete
        show_keys(self, **keys)  # this list's words, on its own bindings (a copy)

    def action_delete_pressed(self) -> None:
        i = self.highlighted
        if self.on_delete is not None and i is not None:
            self.on_delete(self.get_option_at_index(i).id or "")
