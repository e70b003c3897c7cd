"""A file path too long for a line is broken after one of its ``/``, never inside a
name (``touch_`` / ``calibration.json``). Textual wraps a line at spaces and folds a word
longer than the line at its last cell; ``break_paths`` cuts only such a path into
pieces that each fit, a newline after a ``/``: the rest of the text wraps as before (at
any width), the path's pieces each start a line."""

from __future__ import annotations


def _pieces(word: str, width: int) -> list[str]:
    """``word`` cut after its ``/`` into pieces of at most ``width`` cells (a single
    name longer than that stays whole)."""
    parts, cur = [], ""
    for part in word.replace("/", "/\0").split("\0"):
        if cur and len(cur) + len(part) > width:
            parts.append(cur)
            cur = ""
        cur += part
    return [*parts, cur] if cur else parts


def break_paths(text: str, width: int) -> str:
    """``text`` with every path (a word with a ``/``) longer than ``width`` cells cut
    after a ``/`` into lines that fit; everything else as it was."""
    if width < 8:
        return text
    lines = []
    for line in text.split("\n"):
        words = line.split(" ")
        lines.append(
            " ".join(
                "\n".join(_pieces(w, width)) if len(w) > width and "/" in w else w for w in words
            )
        )
    return "\n".join(lines)
