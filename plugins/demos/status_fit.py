"""The Scenes screen's demo status fitted to its rows: each line whole where it fits; a
longer one wraps between whole fields onto the rows the screen has beyond 80 x 24
(``extra_rows``), else drops whole fields (a number is never cut). Every line is said
whole in the log (``console.log``, ``ctrl+l``): what a row could not show is there."""

from __future__ import annotations

from typing import Any

from rich.text import Text

from console.plugin_api.tui import cut_end, status_said, top_level_seps


def log_lines(widget: Any, where: str, markup: str) -> None:
    """``markup``'s lines (plain, whole) into the log as ``where``'s status (each line
    its own: a line's ticks, its numbers only changing, are not logged each time)."""
    for i, line in enumerate(Text.from_markup(markup).plain.split("\n")):
        if line.strip():
            status_said(widget, f"{where} line {i + 1}", line)


def fit_fields(markup: str, width: int, extra_rows: int = 0) -> Text:
    """``markup``'s lines within ``width``: a longer line drops whole fields (parted by
    two spaces, a comma or a semicolon outside brackets), its middle ones first (its
    last one, the end to end latency or the drop counts, stays), "…" where they were;
    a line of one field is cut after a word (``console.tui.shorten``): a number is never
    cut, a bracket never left half. Up to ``extra_rows`` more rows: a longer line wraps
    between whole fields instead (its next row indented)."""
    out: list[Text] = []
    for line in markup.split("\n"):
        text = Text.from_markup(line)
        while text.cell_len > width and extra_rows > 0:
            head, rest = _wrap_at_field(text, width)
            if rest is None:
                break
            out.append(head)
            text, extra_rows = Text("  ") + rest, extra_rows - 1
        out.append(_shorter(text, width))
    return Text("\n").join(out)


def _wrap_at_field(text: Text, width: int) -> tuple[Text, Text | None]:
    """``text``'s first row within ``width``, ended at a field's end, and the rest (None:
    no field ends within ``width``)."""
    seps = [(a, b) for a, b in top_level_seps(text.plain, r"  |, |; ") if a <= width]
    if not seps or seps[-1][0] == 0:
        return text, None
    start, end = seps[-1]
    return text[:start] + Text(text.plain[start:end].rstrip()), text[end:]


def _shorter(text: Text, width: int) -> Text:
    """``text`` within ``width`` by dropping whole fields (``fit_fields``)."""
    if text.cell_len <= width:
        return text
    # fields parted outside brackets only: a dropped field never takes half a bracket
    seps = top_level_seps(text.plain, r"  |, |; ")
    if seps:
        tail = text[seps[-1][1] :]
        for start, _end in reversed(seps[:-1]):  # the head, "…", the last field
            shorter = text[:start] + Text("  …  ") + tail
            if shorter.cell_len <= width:
                return shorter
        for start, _end in reversed(seps):  # the head alone
            shorter = text[:start] + Text(" …")
            if shorter.cell_len <= width:
                return shorter
    # one field, or a first field too long: cut after a whole word, outside brackets
    return text[: cut_end(text.plain, width - 1)] + Text("…")
