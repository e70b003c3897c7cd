"""Number fields that show whole what their check reads: ``NumberField`` takes at most
the characters of the longest number its range allows (``max_length``) and is at least
that wide plus the cursor's cell, so the text shown is the text checked (a new operator
typed ``99999999`` in Gestures' 8-column reps field, saw ``9999999`` and read a refusal
of ``'99999999'``). Its check uses the field's own ``lo`` .. ``hi``: the limit typed
against and the limit said are one."""

from __future__ import annotations

from typing import Any

from textual.widgets import Input

__all__ = ["NumberField", "number_length"]


def number_length(lo: float, hi: float, whole: bool = True, decimals: int = 2) -> int:
    """Characters of the longest number from ``lo`` to ``hi`` (``whole``: integers, else
    with up to ``decimals`` places after the point)."""
    digits = max(len(str(int(lo))), len(str(int(hi))))
    return digits if whole else digits + 1 + decimals


class NumberField(Input):
    """A text field for a number from ``lo`` to ``hi``: any characters typed (a refusal
    names what it takes), at most ``number_length`` of them, all in view."""

    def __init__(
        self,
        value: str = "",
        *,
        lo: float,
        hi: float,
        whole: bool = True,
        decimals: int = 2,
        **kw: Any,
    ) -> None:
        self.lo, self.hi, self.whole = lo, hi, whole
        kw["max_length"] = number_length(lo, hi, whole, decimals)
        super().__init__(value, **kw)

    def on_mount(self) -> None:
        """As wide as its longest text and the cursor's cell, whatever the screen's CSS
        says (a narrower one scrolled the text's start out of view)."""
        self.styles.min_width = self.max_length + 1 + self.styles.gutter.width
