"""A focused list's or table's own keys first in the footer (for a list or table built
elsewhere; ``console.tui.list_keys.KeyedList`` is the list that does it itself).

Textual's ``DataTable`` and ``OptionList`` bind Enter (and their other keys) hidden from
the footer, so a new operator on a list sees the screen's keys but not the one the list
answers to. ``show_keys(widget, enter="use it")`` shows the widget's own binding of a key
with the screen's word for it, on this widget only: the footer lists the focused widget's
keys before the screen's, so they come first while the list has the focus.

A field (a text field, a drop-down) says which one has the focus: ``name_field(widget,
"participant id", enter="next field", escape="leave")`` puts ``participant id:`` first in
the footer while it has the focus, then what those keys do there (keys the field or its
screen answers), as Camera's fields say theirs on their border and Signals' in its hint.
"""

from __future__ import annotations

from dataclasses import replace
from typing import TypeVar
from weakref import WeakKeyDictionary

from textual.widget import Widget
from textual.widgets import Button, Select
from textual.widgets._toggle_button import ToggleButton


def show_keys(widget: Widget, **words: str) -> Widget:
    """Show ``widget``'s own bindings of the keys named (``enter="use it"``,
    ``delete="remove"``) in the footer with those words; returns ``widget``.
    A key the widget does not bind is a mistake of the caller: ``ValueError``."""
    by_key = widget._bindings.key_to_bindings  # this widget's own map (a copy per widget)
    for key, word in words.items():
        bound = by_key.get(key)
        if not bound:
            raise ValueError(f"{type(widget).__name__} has no {key!r} key to show")
        by_key[key] = [replace(b, description=word, show=True) for b in bound]
    return widget


W = TypeVar("W", bound=Widget)

#: the fields named in the footer: (name, (key, word) ...)
_NAMED: WeakKeyDictionary[Widget, tuple[str, tuple[tuple[str, str], ...]]] = WeakKeyDictionary()


def name_field(widget: W, name: str, **words: str) -> W:
    """``widget`` named first in the footer while it has the focus (``name:``), then
    what the keys ``words`` do there (``enter="next field"``, ``escape="leave"``: keys
    the widget or its screen answers; one the widget shows itself is not said twice);
    returns ``widget``."""
    _NAMED[widget] = (name, tuple(words.items()))
    return widget


def field_words(widget: Widget | None) -> tuple[str, tuple[tuple[str, str], ...]] | None:
    """(name, (key, word) ...) of a field ``name_field`` named, else None."""
    return None if widget is None else _NAMED.get(widget)


def shown_words(widget: Widget) -> dict[str, str]:
    """The keys ``widget`` itself shows in the footer, key -> word (for a check)."""
    return {
        key: b.description
        for key, bound in widget._bindings.key_to_bindings.items()
        for b in bound[:1]
        if b.show
    }


def own_key(widget: Widget | None) -> tuple[str, str] | None:
    """(key, word) naming the focused ``widget`` in the footer when it shows no key of its
    own: a button's Enter with its label (``⏎ start``), a check box's Space with its label
    (``space record trials``), a drop-down's Enter (``⏎ choose``). None for any other
    widget, or one that shows its own keys already (``show_keys``)."""
    if widget is None or shown_words(widget):
        return None
    if isinstance(widget, Button):
        return ("enter", _label_word(widget.label))
    if isinstance(widget, ToggleButton):
        return ("space", _label_word(widget.label))
    if isinstance(widget, Select):
        return ("enter", "choose")
    return None


def _label_word(label: object) -> str:
    """A control's label as the footer's word: ``Start`` -> ``start``, ``synthesize (s)``
    -> ``synthesize`` (the key in brackets is the screen's own key, shown beside it)."""
    text = " ".join(str(label).split())
    if text.endswith(")") and " (" in text:
        text = text[: text.rindex(" (")]
    return text[:1].lower() + text[1:]
