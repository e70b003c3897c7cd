"""Drop-downs that offer their choices only: ``Choice`` is Textual's ``Select`` without
its blank entry (``allow_blank=False``: a new operator picked the blank "Select" line of
the Studies protocols and the screen named a protocol and a folder ``Select.NULL``).
Every drop-down the console shows is one (``tests/tui/test_choice.py`` checks the
sources); ``chosen`` reads any ``Select``'s value as text, "" for none. Closed and
narrower than its chosen name, it ends the name with ``…`` (Studies' protocol showed
``threshold_vib ▼``, cut mid-word with nothing saying so)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from textual.widgets import Select

__all__ = ["Choice", "chosen"]


def chosen(value: Any) -> str:
    """A drop-down's value as text; "" when nothing is chosen (Textual's ``Select.NULL``,
    whose text is ``Select.NULL``; ``Select.BLANK`` is not that sentinel in Textual 8)."""
    return "" if value is None or value is Select.NULL else str(value)


class Choice(Select):
    """A ``Select`` whose list holds its options only, the first chosen unless ``value``
    says otherwise; with no option at all it shows its prompt (nothing to choose); a
    name wider than the closed drop-down ends in ``…``."""

    DEFAULT_CSS = """
    Choice SelectCurrent #label { text-wrap: nowrap; text-overflow: ellipsis; }
    """

    def __init__(self, options: Iterable[tuple[Any, Any]], **kw: Any) -> None:
        options = list(options)
        kw.pop("allow_blank", None)
        super().__init__(options, allow_blank=not options, **kw)
