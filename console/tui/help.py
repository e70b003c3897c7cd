"""The help screen's text: shown as written, wrapped to the terminal.

A screen's help (``HELP_TEXT``) is plain text, never markup: ``[console] image`` and
``[ / ]`` keep their brackets. It is written as paragraphs, one line each: an entry
starts with its key and two spaces or a colon (``b        capture the background``,
``s: synthesize ...``), anything else is prose. The widget wraps each paragraph to the
width it has, an entry's lines under its description (a hanging indent), so no word is
left alone on a line at any width. A help written with hard line breaks is joined back
into its paragraphs first (a line that starts indented, or lower-case and not as an
entry, continues the line above), so every pane's help reads well at 80 and 120 columns.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

from textual.content import Content
from textual.widgets import Static

from console.tui import glue

__all__ = ["ENTRY", "HelpText", "columns", "help_text", "paragraphs", "wrap"]

#: the start of an entry: its key (a word, or a few short ones: ``t / T``, ``w a s d``,
#: ``n / Analyse``; the fewest that reach a separator, so ``b: build the lookup tables``
#: is the key ``b``) then two spaces or ``": "``, then its description
ENTRY = re.compile(r"^(?P<key>\S{1,12}?(?: \S{1,8}?){0,4}?)(?P<sep>: |\s{2,})(?=\S)")
#: an entry's description starts at most this far right to be wrapped under itself
MAX_HANG = 18


def _continues(line: str) -> bool:
    """Whether ``line`` (of a hard-wrapped help) continues the line above."""
    if line[0].isspace():
        return True
    return (line[0].islower() or line[0].isdigit() or line[0] == "(") and not ENTRY.match(line)


#: where a second entry starts on a line (``b: build ...   x: cancel ...``): three or
#: more spaces, then an entry's key and its separator
NEXT_ENTRY = re.compile(r"(?<=\S)\s{3,}(?=" + ENTRY.pattern.lstrip("^") + ")")


def entries(line: str) -> list[str]:
    """``line`` cut where another entry starts after three or more spaces: each entry
    is a paragraph of its own (two side by side ran together into one sentence once
    wrapped: ``x: cancel what runs page down / page up: ...``)."""
    m = ENTRY.match(line)  # the line's own key and its separator stay
    cut = NEXT_ENTRY.search(line, m.end() if m is not None else 0)
    if cut is None:
        return [line]
    return [line[: cut.start()], *entries(line[cut.end() :])]


def paragraphs(text: str) -> list[str]:
    """``text`` as its paragraphs: one line per entry or paragraph, ``""`` for a blank
    line; hard line breaks inside a paragraph are joined back, and entries written side
    by side are cut apart (see the module)."""
    out: list[str] = []
    for whole in text.splitlines():
        first, *more = entries(whole.rstrip()) if whole.strip() else [whole]
        out += _joined(out, first)
        out += more
    return out


def _joined(out: list[str], raw: str) -> list[str]:
    """The paragraphs ``raw`` adds to ``out``: none when it continues ``out``'s last
    one (joined to it there), else itself (``""``: a blank line)."""
    line = raw.rstrip()
    if not line.strip():
        return [""]
    if out and out[-1] and _continues(line):
        out[-1] = f"{out[-1]} {line.strip()}"
        return []
    return [line]


def columns(paras: list[str]) -> list[str]:
    """Runs of two or more entries written one under the other as one table: each key
    padded to the run's widest (at most ``MAX_HANG`` wide with its gap, a colon kept), so
    the descriptions start in one column whichever way a screen's help was written
    (``c / C  contact`` under ``t / T    body``; ``enter:   audition`` under ``arrows:``)."""
    found = [ENTRY.match(p) if p else None for p in paras]
    # a key as written: its colon kept (the help shows its words as written)
    keys = [m.group("key") + m.group("sep").rstrip() if m else None for m in found]
    keys = [k if k is not None and len(k) + 2 <= MAX_HANG else None for k in keys]
    out, i = list(paras), 0
    while i < len(paras):
        j = i
        while j < len(paras) and keys[j] is not None:
            j += 1
        if j - i >= 2:
            col = max(len(keys[k]) for k in range(i, j)) + 2
            for k in range(i, j):
                out[k] = keys[k].ljust(col) + paras[k][found[k].end() :]
        i = max(j, i + 1)
    return out


def wrap(paragraph: str, width: int) -> list[tuple[str, str]]:
    """``paragraph`` wrapped to ``width`` columns as ``(key, rest)`` line pieces: the
    first line of an entry has its key apart (shown bold), the others ``("", line)``."""
    if not paragraph:
        return [("", "")]
    width = max(width, 8)
    m = ENTRY.match(paragraph)
    key = m.group(0) if m is not None else ""
    hang = len(key) if key and len(key) <= min(MAX_HANG, width // 2) else 0
    if hang and max(map(len, paragraph[len(key) :].split()), default=0) > width - hang:
        hang = 0  # a word wider than the column (a path): the lines wrap whole
    body = paragraph[len(key) :] if hang else paragraph
    lines = glue.wrap(
        body,
        width - hang,
        break_on_hyphens=False,
        drop_whitespace=True,
        replace_whitespace=False,
    ) or [""]
    if not hang:
        if key:  # a long key: the line wraps whole, the key still bold
            first = lines[0]
            cut = min(len(key.rstrip()), len(first))
            return [(first[:cut], first[cut:])] + [("", ln) for ln in lines[1:]]
        return [("", ln) for ln in lines]
    return [(key, lines[0])] + [("", " " * hang + ln) for ln in lines[1:]]


def help_text(body: str, width: int = 76, title: str = "") -> Content:
    """``body`` (a help as written) wrapped to ``width``, literal, keys bold; ``title``
    (bold) above it."""
    return _content([(title, body)], width)


def _content(sections: Sequence[tuple[str, str]], width: int) -> Content:
    lines: list[Content] = []
    for title, body in sections:
        if title:
            if lines:
                lines.append(Content(""))
            lines.append(Content.styled(title, "bold"))
        for para in columns(paragraphs(body)):
            for key, rest in wrap(para, width):
                lines.append(Content.assemble((key, "bold"), rest) if key else Content(rest))
    return Content("\n").join(lines)


class HelpText(Static):
    """Help sections (title, text as written) wrapped to the widget's width."""

    DEFAULT_CSS = "HelpText { width: 1fr; height: auto; }"

    def __init__(self, sections: Sequence[tuple[str, str]], **kw) -> None:
        super().__init__(**kw)
        self.sections = list(sections)

    def render(self) -> Content:
        return _content(self.sections, self.content_size.width or 76)

    def get_content_width(self, container, viewport) -> int:
        return container.width

    def get_content_height(self, container, viewport, width: int) -> int:
        return len(_content(self.sections, width).plain.split("\n"))
