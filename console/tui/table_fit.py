"""A table's columns sized to the width it has: a cell within its column, on one line
ending in "…" after a whole word when cut (``clip``), or wrapped inside its row
(``fit_cell``; in a few lines at most: ``fit_lines``), never cut at the screen's edge
mid-word; the widths of the last columns shared (``share``)."""

from __future__ import annotations

from rich.text import Text

from console.tui.kept_text import wrap_kept
from console.tui.shorten import closers, cut_words

#: the narrowest a column sized from what is left gets
NOTE_MIN = 6


def clip(text: str, width: int) -> str:
    """``text`` on one line within ``width`` columns, ending in "…" when cut after a
    whole word (a first word wider than the column cut where it must), no bracket left
    open (``console.tui.shorten``): ``no Yocto-MaxiCoupler…``, never ``… onl…``."""
    return cut_words(" ".join(str(text).split()), width)


def _word_fits(word: str, width: int) -> str:
    """``word`` as wrapping can show it within ``width``: whole when each of its pieces
    after a "/" fits (a path breaks there), else cut at the piece too long, ending in
    "…" (never a word broken mid-letters over lines)."""
    if len(word) <= width:
        return word
    start = 0
    while start < len(word):
        end = word.find("/", start)
        end = len(word) if end < 0 else end + 1
        if end - start > width:
            return word[: start + width - 1] + "…"
        start = end
    return word


def fit_cell(text: str, width: int) -> Text:
    """``text`` wrapped within ``width`` columns (a number and its unit kept together,
    a path broken after a "/"), a word too long for a line ending in "…"."""
    words = [_word_fits(w, width) for w in str(text).split()]
    return wrap_kept(" ".join(words), width)


def fit_lines(text: str, width: int, lines: int) -> Text:
    """``text`` wrapped as ``fit_cell`` does in at most ``lines`` lines: what does not
    fit is cut after a whole word, ending in "…" (and what closes a bracket it cut)."""
    wrapped = fit_cell(text, width)
    if len(wrapped.plain.split("\n")) <= lines:
        return wrapped
    words = str(text).split()
    for k in range(len(words) - 1, 0, -1):  # whole words dropped from the end
        head = " ".join(words[:k]).rstrip(",;:-")
        shorter = fit_cell(f"{head}…{closers(head)}", width)  # a bracket cut: "…)"
        if len(shorter.plain.split("\n")) <= lines:
            return shorter
    return Text(cut_words(" ".join(words), width))


def share(left: int, needs: tuple[int, int]) -> tuple[int, int]:
    """Two last columns' widths within ``left`` columns (with the 2 between them), from
    the widest text or header of each: both whole when they fit, else the narrower one
    kept up to half and the rest to the other; never under ``NOTE_MIN``."""
    room = left - 2
    a, b = needs
    if a + b <= room:
        return a, b
    if a <= b:
        a = max(NOTE_MIN, min(a, room // 2))
        return a, max(NOTE_MIN, room - a)
    b = max(NOTE_MIN, min(b, room // 2))
    return max(NOTE_MIN, room - b), b


def widths(heads, rows: list[list]) -> list[int]:
    """Each column's width: its widest cell or its header."""
    return [max(len(str(c)) for c in [h, *col]) for h, *col in zip(heads, *rows, strict=True)]


def need(head: str, texts) -> int:
    """A column's width: its widest text on one line, or its header."""
    widest = max((len(" ".join(str(t or "").split())) for t in texts), default=0)
    return max(widest, len(head))
