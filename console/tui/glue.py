"""A number stays on the line of its unit and of its label: ``0 s``, ``(1 s)``, ``fps
54.08``, ``2.72 mm`` never break across a line wrap (an operator read ``... 0`` / ``s`` at
80 columns); a key stays with the word it names: ``S: save``, ``x: cancel`` (a
calibration's result read ``S:`` / ``save``). One rule, ``stays_together``, applied
where the console's text is wrapped:

- by Textual (every ``Static``, ``Label``, the log): its lines are cut between the words
  Rich's ``divide_line`` finds; ``install`` makes those words glue-aware (a glued pair is
  one word), done when ``console.tui`` is imported;
- by the console's own wrapping (the help screen, a message in place of the camera
  view): ``wrap``, ``textwrap.wrap`` with the same rule; the Camera screen's live
  numbers (``camera_live.hang``) wrap the ``groups`` of a line.

The text itself is unchanged (a plain space between number and unit: what a test reads,
what a copy from the terminal gives)."""

from __future__ import annotations

import re
import textwrap
from collections.abc import Callable, Iterable

__all__ = ["groups", "install", "stays_together", "wrap"]

#: a word that is a number, maybe opened by a bracket or a sign (``(1``, ``~3``, ``-15``)
NUMBER = re.compile(r"[(\[~≈<>=±+−-]*\d+(?:[.,:]\d+)*")
#: a unit after a number (maybe closed by a bracket or punctuation: ``s)``, ``mm;``)
UNIT = re.compile(
    r"(?:s|ms|us|µs|min|h|Hz|kHz|MHz|mm|cm|m|um|µm|nm|V|mV|kV|Vpp|V/s|A|mA|dB|dBFS|%|"
    r"px|fps|deg|°|g|N|B|kB|MB|GB|samples|frames)[)\].,;:!?]*"
)
#: a label before a number (``fps 54.08``, ``rms 0.61``, ``p99 2.1``)
LABEL = re.compile(
    r"(?:fps|rms|max|min|mean|median|peak|p\d{1,2}|gain|exposure|error|latency|level)[:=]?",
    re.IGNORECASE,
)
#: a key and its colon before the word it names (``S: save``, ``Esc: back``, ``F6: Scenes``)
KEY = re.compile(r"(?:[A-Za-z]|Esc|Enter|Tab|Space|F\d{1,2}|ctrl\+[a-z])[:]")
#: a glued group longer than this breaks as words do (a line is never overfull for it)
MAX_GLUED = 24


def stays_together(left: str, right: str) -> bool:
    """Whether the words ``left`` and ``right`` (a space apart) stay on one line: a
    number and its unit, a label and its number, a key and the word it names."""
    if NUMBER.fullmatch(left):
        return bool(UNIT.fullmatch(right))
    if KEY.fullmatch(left):
        return bool(right)
    return bool(LABEL.fullmatch(left)) and bool(NUMBER.match(right))


def _joins(before: str, after: str) -> bool:
    """Whether the pieces of text ``before`` and ``after`` (words, ``before`` without
    its trailing space) are one glued group for a wrapper."""
    a, b = before.split(), after.split()
    return bool(a and b) and stays_together(a[-1], b[0]) and len(f"{before} {after}") <= MAX_GLUED


def _glued(words: Iterable[str]) -> list[str]:
    """``words`` (each with the white space after it) with the glued ones joined."""
    out: list[str] = []
    for word in words:
        last = out[-1] if out else ""
        if last.endswith(" ") and not last.endswith("  ") and _joins(last[:-1], word.strip()):
            out[-1] = last + word
        else:
            out.append(word)
    return out


def groups(line: str) -> list[str]:
    """``line``'s words (split at single spaces, as ``str.split(" ")``) with the glued
    ones joined by their space: the pieces a wrapper may put on separate lines."""
    return [g[:-1] for g in _glued(f"{w} " for w in line.split(" "))]


def _glued_words(
    words: Callable[[str], Iterable[tuple[int, int, str]]],
) -> Callable[[str], Iterable[tuple[int, int, str]]]:
    """Rich's ``words`` (start, end, word with its trailing spaces) with glued ones
    joined into one."""

    def glued(text: str) -> Iterable[tuple[int, int, str]]:
        start = 0
        for word in _glued(w for _, _, w in words(text)):
            yield start, start + len(word), word
            start += len(word)

    return glued


#: the glue-aware ``words`` put in Rich's place (``install``)
_INSTALLED: list[Callable[[str], Iterable[tuple[int, int, str]]]] = []


def install() -> None:
    """Textual's line wrapping (Rich's ``divide_line``) keeps glued words together."""
    import rich._wrap as rich_wrap

    if rich_wrap.words not in _INSTALLED:  # once
        rich_wrap.words = _glued_words(rich_wrap.words)
        _INSTALLED.append(rich_wrap.words)


class _Wrapper(textwrap.TextWrapper):
    """``textwrap`` that keeps glued words together."""

    def _split(self, text: str) -> list[str]:
        out: list[str] = []
        for chunk in super()._split(text):
            if len(out) >= 2 and out[-1] == " " and _joins(out[-2], chunk):
                out[-2:] = [f"{out[-2]} {chunk}"]
            else:
                out.append(chunk)
        return out


def wrap(text: str, width: int, **kw: object) -> list[str]:
    """``textwrap.wrap(text, width, **kw)`` that never breaks between glued words."""
    return _Wrapper(width=width, **kw).wrap(text)  # type: ignore[arg-type]
