"""Keys typed right after a key that opens a text field go to that field, in order.

Textual runs a screen's (non-priority) binding only when its key has bubbled back to the
app, after the keys typed behind it were handed to the widget that had the focus then:
``o/tmp/x`` in one write (tmux send-keys, a fast typist) opened an empty field while
``/tmp/x`` ran as the screen's keys (``e``, ``u``, ``t`` ...). An action marked
``@opens_field`` runs when its key arrives (``run_at_once``, from the app's ``on_event``),
and shows its field with ``show_field``, which gives it the focus at once (``focus()``
waits for the keys already queued): the keys behind it are the field's, replacing
what the field opened with (selected).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

from textual.widgets import Input

F = TypeVar("F", bound=Callable[..., Any])


#: the ``action_...`` functions marked ``@opens_field``
_OPENERS: set[Callable[..., Any]] = set()


def opens_field(action: F) -> F:
    """Mark ``action_...`` as one that opens a text field (``run_at_once`` runs it)."""
    _OPENERS.add(action)
    return action


def _opener(node: Any, action: str) -> bool:
    """Whether ``node``'s ``action_<action>`` (as its class resolves it) opens a field."""
    name = f"action_{action}"
    found = next((vars(k)[name] for k in type(node).__mro__ if name in vars(k)), None)
    return found in _OPENERS


def show_field(field: Input) -> None:
    """``field`` shown with the focus given now, not after the keys queued meanwhile, and
    what it opens with (the value in use, a refused one as typed) selected, as in a
    dialog's prefilled field: a key typed replaces it, an arrow keeps it to edit (the
    cursor at its end had ``U`` then a target make ``127.0.0.1:3333host:port``)."""
    field.display = True
    field.screen.set_focus(field)
    field.select_all()


async def run_at_once(app: Any, key: str) -> bool:
    """Run the focused widget's binding for ``key`` now if its action opens a field;
    whether it ran. The binding is the one Textual would run (the first one allowed on
    the way from the focused widget up to the screen)."""
    focused = app.focused
    if focused is None or isinstance(focused, Input):
        return False
    for node in focused.ancestors_with_self:
        for binding in node._bindings.key_to_bindings.get(key, ()):
            if binding.priority or not node.check_action(binding.action, ()):
                continue
            if not _opener(node, binding.action):
                return False
            await app.run_action(binding.action, node)
            return True
    return False
