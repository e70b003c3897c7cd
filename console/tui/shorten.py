"""Text shortened for a width the way a reader can take it: after a whole word, never
inside a bracket whose end is cut away, so no line is left with an unmatched ``(`` or
``)`` (Scenes' last-run line once ended ``… 0.25 s) - ctrl+r resets``: a field was
dropped from inside a bracket). The toasts (``console.tui.toasts``), the safety bar,
table cells (``console.tui.table_fit``) and the Scenes status (``fit_fields``) shorten
through these."""

from __future__ import annotations

import re

from rich.cells import cell_len

__all__ = [
    "balanced",
    "closers",
    "cut_chars",
    "cut_end",
    "cut_words",
    "lead",
    "top_level_seps",
]

OPENS = "([{"
CLOSES = ")]}"
ELLIPSIS = "…"


def _depths(plain: str) -> list[int]:
    """The bracket depth before each character of ``plain`` (never below 0)."""
    depth, out = 0, []
    for ch in plain:
        out.append(depth)
        if ch in OPENS:
            depth += 1
        elif ch in CLOSES:
            depth = max(0, depth - 1)
    return out


def balanced(plain: str) -> bool:
    """Whether every bracket of ``plain`` is closed and every closing one opened."""
    stack: list[str] = []
    for ch in plain:
        if ch in OPENS:
            stack.append(CLOSES[OPENS.index(ch)])
        elif ch in CLOSES and (not stack or stack.pop() != ch):
            return False
    return not stack


def _unclosed(plain: str) -> list[int]:
    """Where the brackets of ``plain`` that it leaves open start, outermost first."""
    stack: list[int] = []
    for i, ch in enumerate(plain):
        if ch in OPENS:
            stack.append(i)
        elif ch in CLOSES and stack:
            stack.pop()
    return stack


def top_level_seps(plain: str, pattern: str) -> list[tuple[int, int]]:
    """The (start, end) of each match of ``pattern`` outside any bracket: where a line
    may be parted into fields without leaving half a bracket on either side."""
    depth = _depths(plain)
    return [(m.start(), m.end()) for m in re.finditer(pattern, plain) if depth[m.start()] == 0]


def lead(plain: str) -> str:
    """The first clause of ``plain``, up to its first ``;`` outside a bracket: where a
    line says its reason (``quick self-test skipped (no baseline yet: ...)``), which a
    shortened line keeps whole (the rest gives way to it)."""
    seps = top_level_seps(plain, r";")
    return plain[: seps[0][0]] if seps else plain


def cut_end(plain: str, room: int) -> int:
    """Where to cut ``plain`` so that its head fits ``room`` cells: after its last whole
    word that fits, and before a bracket the cut would leave open (the bracket's words
    go with it); a first word wider than ``room`` is cut where it must."""
    end = 0
    while end < len(plain) and cell_len(plain[: end + 1]) <= room:
        end += 1
    if end < len(plain) and not plain[end].isspace():  # mid-word: back to the last space
        space = plain.rfind(" ", 0, end)
        if space > 0 and plain[:space].strip():
            end = space
    left_open = _unclosed(plain[:end])
    if left_open:  # the outermost bracket left open: cut before it
        end = left_open[0]
    while end > 0 and plain[end - 1] in " ,;:-|":
        end -= 1
    return end if end > 0 else min(len(plain), max(room, 0))


def cut_words(text: str, width: int, ellipsis: str = ELLIPSIS) -> str:
    """``text`` whole when it fits ``width`` cells, else its head cut by ``cut_end``
    ending in ``ellipsis``."""
    if cell_len(text) <= width:
        return text
    end = cut_end(text, max(width - cell_len(ellipsis), 0))
    return text[:end].rstrip() + ellipsis


def cut_chars(text: str, width: int, ellipsis: str = ELLIPSIS) -> str:
    """``text`` whole when it fits ``width`` cells, else cut where the width ends (a
    narrow table cell keeps the letters it can: ``1 ou…``) ending in ``ellipsis``, but
    before a bracket the cut would leave open, when that keeps some text."""
    if cell_len(text) <= width:
        return text
    head = text[: max(width - cell_len(ellipsis), 0)]
    left_open = _unclosed(head)
    if left_open and text[: left_open[0]].strip():
        head = text[: left_open[0]]
    return head.rstrip(" ,;:-|") + ellipsis


def closers(head: str) -> str:
    """What closes the brackets ``head`` leaves open, innermost first: a head cut inside
    a bracket ends ``…)`` and stays balanced."""
    return "".join(CLOSES[OPENS.index(head[i])] for i in reversed(_unclosed(head)))
