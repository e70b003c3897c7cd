"""A footer that shows which keys work now. A screen says why an action is refused
(``key_refusal``: its one check, the one the action itself makes); the footer shows a
refused key dimmed (``check_action`` gives None: Textual then runs no action for it),
and the key still answers with the reason (``answer_refused``, from the screen's
``on_key``, which sees the key before the bindings do). ``refusals_changed`` refreshes
the footer only when what is refused changed (``refusal_state``): a screen calls it
where it already notices its state, no work of its own while nothing changed."""

from __future__ import annotations

from collections.abc import Hashable
from typing import Any


def action_name(action: str) -> str:
    """``tune('body', 1)`` -> ``tune`` (a binding's action without its arguments)."""
    return action.split("(", 1)[0].rsplit(".", 1)[-1]


class RefusedKeys:
    """Mixed into a screen (a Textual widget with ``BINDINGS``): override
    ``key_refusal``, ``refusal_state`` and ``say_refused``; call ``key_dimmed`` from
    ``check_action``, ``answer_refused`` first in ``on_key`` and ``refusals_changed``
    when the state may have changed."""

    _refused_state: Hashable = None

    def key_refusal(self, action: str) -> str:
        """Why ``action``'s key is refused now ("" when it works)."""
        return ""

    def refusal_state(self) -> Hashable:
        """What the refusals depend on, cheap to read (a demo's name, a holder)."""
        return None

    def say_refused(self, key: str, why: str) -> None:
        """Say on the screen that ``key`` was refused, ``why``."""

    def key_dimmed(self, action: str) -> bool | None:
        """For ``check_action``: None (shown dimmed) when ``action`` is refused now."""
        return None if self.key_refusal(action) else True

    def refusals_changed(self) -> bool:
        """Refresh the footer if what is refused changed since it was drawn (True)."""
        state = self.refusal_state()
        if state == self._refused_state:
            return False
        self._refused_state = state
        self.refresh_bindings()  # type: ignore[attr-defined]
        return True

    def answer_refused(self, event: Any) -> bool:
        """A key bound here whose action is refused now: say why, stop the key (True);
        else False (the binding runs as usual)."""
        bindings = self._bindings.key_to_bindings.get(event.key, ())  # type: ignore[attr-defined]
        for binding in bindings:
            why = self.key_refusal(action_name(binding.action))
            if why:
                event.stop()
                event.prevent_default()
                self.say_refused(event.character or binding.key_display or event.key, why)
                return True
        return False
