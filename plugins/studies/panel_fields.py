"""The Studies screen's fields say themselves: while one has the focus the footer names
it first (``participant id:``) with what Enter and Esc do there (``console.tui.
focus_keys.name_field``), as the Camera and Signals fields say theirs. Enter in a text
field moves on to the next Tab stop, what was typed kept; Esc leaves for Start
(``StudiesPane.action_leave_field``)."""

from __future__ import annotations

from typing import Any

from textual.widgets import Input

from console.plugin_api.tui import name_field

#: each field's id and the name the footer gives it (the label beside it)
FIELD_NAMES = {
    "protocol": "protocol",
    "participant": "participant id",
    "out": "folder",
    "age": "age",
    "sex": "sex",
    "handedness": "handedness",
    "hand_width_cm": "hand width cm",
    "hand_length_cm": "hand length cm",
}
#: what Enter and Esc do in a text field (the drop-down's Enter lists its protocols)
TEXT_KEYS = {"enter": "next field", "escape": "leave"}


class FieldKeys:
    """The Studies pane's fields named in the footer, Enter in one moving on."""

    screen: Any

    def on_mount(self) -> None:
        for wid, name in FIELD_NAMES.items():
            for field in self.query(f"#{wid}"):  # type: ignore[attr-defined]
                keys = TEXT_KEYS if isinstance(field, Input) else {"escape": "leave"}
                name_field(field, name, **keys)

    def on_input_submitted(self, event: Input.Submitted) -> None:
        """Enter in a field: the next Tab stop (what was typed stays)."""
        if event.input.id in FIELD_NAMES:
            event.stop()
            self.screen.focus_next()
