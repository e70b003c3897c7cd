"""The Gestures panel's typed fields, kept for the console's run: the panel is built
anew each time it opens, and what the operator typed (subjects 2, reps 2) shows again."""

from __future__ import annotations

from typing import Any
from weakref import WeakKeyDictionary

#: each console run's fields (its context: the run's), by field id (``gp-reps``)
_KEPT: WeakKeyDictionary[Any, dict[str, str]] = WeakKeyDictionary()


def kept_fields(run: Any) -> dict[str, str]:
    """The fields typed in the console's run ``run`` (its context), a dict the panel
    updates as they change; empty for a run that cannot be weakly referenced."""
    try:
        return _KEPT.setdefault(run, {})
    except TypeError:
        return {}
