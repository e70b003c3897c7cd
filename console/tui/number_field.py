"""Number fields that keep every character typed: ``NumberField`` is at least as wide as
the longest number its range allows (``longest``) plus the cursor's cell, and a longer
text scrolls in it, never cut (a field that took at most ``longest`` characters turned a
typed ``abc`` into ``ab`` and ``99999999999`` into ``999`` without a word). Its check
uses the field's own ``lo`` .. ``hi`` and quotes the whole text the field holds: the
limit typed against and the limit said are one."""

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
    """A text field for a number from ``lo`` to ``hi``: any characters typed, as many as
    typed (a refusal quotes them and names what it takes), its longest number in view."""

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
        #: characters of the longest number the field takes (its width, with the cursor)
        self.longest = number_length(lo, hi, whole, decimals)
        kw.pop("max_length", None)  # what is typed is kept: the check refuses, quoting it
        super().__init__(value, **kw)

    def on_mount(self) -> None:
        """As wide as its longest number and the cursor's cell, whatever the screen's CSS
        says (a narrower one scrolled a number's start out of view)."""
        self.styles.min_width = self.longest + 1 + self.styles.gutter.width
