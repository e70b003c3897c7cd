"""Lines wrapped without cutting what belongs together: a key and its word (``t:
waveform``, ``+ -: amplitude``), a number and its unit (``0.0 V peak``, ``64
samples``). Textual wraps at any space, so at 80 columns a hint ended in ``t:`` with
``waveform`` alone on the next line.

Words joined by a no-break space (``NBSP``: ``yours:\u00a0open``, ``(pid\u00a04242)``)
are one group too: the writer says what must not part.

``kept_breaks`` finds where a line may break; ``wrap_kept`` wraps a Rich ``Text`` (its
styles kept) at those places only; ``KeptText`` is a ``Static`` that does it at its
width, whatever the terminal's size.
"""

from __future__ import annotations

import re

from rich.measure import Measurement
from rich.text import Text
from textual.widgets import Static

#: units a number keeps on its line (a number and its unit are one thing to read)
UNITS = frozenset(
    [
        "V",
        "Vpp",
        "mV",
        "Hz",
        "kHz",
        "mm",
        "cm",
        "m",
        "ms",
        "s",
        "min",
        "h",
        "dB",
        "%",
        "mN",
        "N",
        "um",
        "um/V",
        "µm",
        "µm/V",
        "nm",
        "px",
        "deg",
        "samples",
        "bins",
        "x",
        "points",
        "rows",
        "columns",
        "frames",
        "MB",
        "GB",
        "kB",
    ]
)
#: words a unit keeps after it (``12.3 V peak``)
AFTER_UNIT = frozenset(["peak", "mean", "RMS", "rms"])
#: keys named by a word
KEY_NAMES = frozenset(
    [
        "enter",
        "esc",
        "escape",
        "tab",
        "space",
        "delete",
        "home",
        "end",
        "up",
        "down",
        "left",
        "right",
    ]
)
#: a key's label at most this long (``enter:``, ``ctrl+r:``); a longer "word:" is prose
KEY_MAX = 7
#: a key's item (``m: measure``, ``b: build the lookup tables``) at most this long is
#: kept on one line
ITEM_MAX = 28
#: a no-break space: the words either side of it stay on one line (``keep``)
NBSP = "\u00a0"
_NUMBER = re.compile(r"^[(~≈<>≤≥+\-−]?\d[\d.,]*$")
_WORD = re.compile(r"(?:[^\s]|\u00a0)+")  # a no-break space is inside a word


def keep(*words: str) -> str:
    """``words`` joined by no-break spaces: ``KeptText`` never breaks between them."""
    return NBSP.join(words)


def _is_key(tok: str) -> bool:
    """A key's label: ``t:``, ``]:``, ``enter:``, ``ctrl+r:`` (not a word ending a
    clause: ``passive:``, ``mm):``)."""
    body = tok[:-1].lower()
    if not tok.endswith(":") or len(tok) > KEY_MAX + 1:
        return False
    return len(body) <= 2 or body in KEY_NAMES or body.startswith(("ctrl+", "shift+", "alt+"))


def _glued(a: str, b: str, after: str | None) -> bool:
    """Whether the space between tokens ``a`` and ``b`` (``after``: the token after
    ``b``) must not break."""
    if _is_key(a):  # a key and the first word it names
        return True
    if _is_key(b) and len(b) <= 3 and len(a) <= 2:  # "+ -:", "[ ]:": the key's pieces
        return True
    if len(a) == 1 and len(b) == 1 and after is not None and (_is_key(after) or len(after) == 1):
        return True  # "w a" of "w a s d:"
    if _NUMBER.match(a) and b.rstrip(",;.):") in UNITS:
        return True
    if a[-1].isalpha() and _NUMBER.match(b) and after and after.rstrip(",;.):") in UNITS:
        return True  # what is measured and its value: "screen 0.0 V"
    return a in UNITS and b.rstrip(",;.):") in AFTER_UNIT


def _items(line: str, words: list[tuple[int, int]]) -> list[int]:
    """Per word of ``line``, its item's number when the item is a short keyed one
    (``b: build the lookup tables``: items are parted by two spaces or more), else -1."""
    out, item = [], 0
    for i, (s, _e) in enumerate(words):
        if i and line[words[i - 1][1] : s].count(" ") >= 2:
            item += 1
        out.append(item)
    spans: dict[int, tuple[int, int]] = {}
    for i, it in enumerate(out):
        a, _ = spans.get(it, (i, i))
        spans[it] = (a, i)
    keyed = {
        it
        for it, (a, b) in spans.items()
        if words[b][1] - words[a][0] <= ITEM_MAX
        and any(_is_key(line[slice(*words[j])]) for j in range(a, min(a + 4, b + 1)))
    }
    return [it if it in keyed else -1 for it in out]


def kept_breaks(line: str, width: int) -> list[int]:
    """Offsets in ``line`` (no newline in it) where its wrapped lines start, breaking only
    at spaces not inside a kept group; a group wider than ``width`` breaks inside (a path
    after one of its ``/``, as ``console.tui.wrap_paths`` does)."""
    words = [(m.start(), m.end()) for m in _WORD.finditer(line)]
    if width <= 0 or len(line) <= width or not words:
        return []
    items = _items(line, words)
    # groups of words that stay together: (start, end) offsets
    groups: list[list[int]] = []
    for i, (s, e) in enumerate(words):
        tok = line[s:e]
        prev = line[words[i - 1][0] : words[i - 1][1]] if i else None
        after = line[words[i + 1][0] : words[i + 1][1]] if i + 1 < len(words) else None
        same = i and items[i] >= 0 and items[i] == items[i - 1]  # a short keyed item
        if prev is not None and (same or _glued(prev, tok, after)) and e - groups[-1][0] <= width:
            groups[-1][1] = e
        else:
            groups.append([s, e])
    starts, line_start, at = [], groups[0][0], [0]  # at: each line's first group
    for i, (s, e) in enumerate(groups):
        if i and e - line_start > width:
            starts.append(s)
            line_start = s
            at.append(i)
        while e - line_start > width:  # a word longer than the line: after a "/" if it can
            cut = line.rfind("/", line_start, line_start + width)
            line_start = cut + 1 if cut > line_start else line_start + width
            starts.append(line_start)
    # no word left alone on the last line: its line before gives it a word when it has
    # three or more and the two fit
    last = len(at) > 1 and at[-1] == len(groups) - 1 and starts[-1] == groups[-1][0]
    last = last and " " not in line[groups[-1][0] : groups[-1][1]]  # one word alone
    if last and at[-1] - at[-2] >= 3:
        s = groups[at[-1] - 1][0]
        if groups[-1][1] - s <= width:
            starts[-1] = s
    return starts


def wrap_kept(text: Text | str, width: int) -> Text:
    """``text`` wrapped at ``width`` columns (its newlines kept), never between a key
    and its word or a number and its unit; trailing spaces of a wrapped line dropped."""
    text = Text(text) if isinstance(text, str) else text
    out = []
    for line in text.split("\n", allow_blank=True):
        breaks = kept_breaks(line.plain, width)
        if not breaks:
            out.append(line)
            continue
        for piece in line.divide(breaks):
            piece.rstrip()
            out.append(piece)
    return Text("\n").join(out)


class KeptText(Static):
    """A ``Static`` whose lines wrap at its width without cutting a key from its word or
    a number from its unit (``wrap_kept``). ``markup`` as for ``Static``."""

    def __init__(self, text: str = "", *, markup: bool = True, **kw) -> None:
        super().__init__("", markup=markup, **kw)
        self._kept_markup = markup
        self.kept = text
        super().update(self._text())

    def _text(self) -> Text:
        return Text.from_markup(self.kept) if self._kept_markup else Text(self.kept)

    def update(self, content="", *, layout: bool = True) -> None:  # noqa: D102
        self.kept = str(content)
        super().update(self._text(), layout=layout)

    def get_content_height(self, container, viewport, width: int) -> int:
        return len(wrap_kept(self._text(), width).plain.split("\n")) if self.kept else 0

    def render(self):
        return Kept(self._text())


class Kept:
    """A Rich renderable: ``text`` wrapped by ``wrap_kept`` at the width it is drawn in;
    ``str()`` of it is the text as written (unwrapped)."""

    def __init__(self, text: Text) -> None:
        self.text = text

    def __str__(self) -> str:
        return self.text.plain

    def __rich_console__(self, console, options):
        yield wrap_kept(self.text, options.max_width)

    def __rich_measure__(self, console, options) -> Measurement:
        widest = max((len(line) for line in self.text.plain.split("\n")), default=0)
        return Measurement(1, min(widest, options.max_width))
