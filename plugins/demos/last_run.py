"""The Scenes screen's last-run block (how the demo ended, its last numbers, where the
twin's outputs went) as a function of the width it is shown at: laid out again whenever
that width changes (a resized terminal), and whole in the log (``LOG_WIDTH``)."""

from __future__ import annotations

import textwrap
from collections.abc import Callable

from console.plugin_api.tui import escape, middle_ellipsis, short_path, whole_names

#: the width the log's copy is laid out at: nothing wrapped or cut
LOG_WIDTH = 10_000

#: markup for the width (the app's columns) it is shown at
Layout = Callable[[int], str]


def never_ran(said: str) -> Layout:
    """A run with no numbers: ``said`` (``knob stopped by s``) wrapped to the width."""
    return lambda width: escape("\n".join(textwrap.wrap(said, width - 2)))


def last_run(head: str, numbers: str, twin_log: str | None) -> Layout:
    """``last run (HEAD):`` wrapped, the run's last ``numbers`` (markup, fitted where
    shown) and ``the twin's outputs received: PATH``, its path cut between whole names
    (a name cut inside reads as a wrong path): a line of its own when its file name
    does not fit after the label."""

    def at(width: int) -> str:
        cols = width - 2  # the pane's scrollbar
        text = numbers
        if twin_log:
            label, path = "the twin's outputs received: ", short_path(twin_log)
            shown = whole_names(path, cols - len(label))
            if shown is None:
                label, shown = label.rstrip() + "\n", whole_names(path, cols)
            text += f"\n{label}{escape(shown or middle_ellipsis(path, cols))}"
        wrapped = "\n".join(textwrap.wrap(f"last run ({head}):", cols))
        return f"{escape(wrapped)}\n{text}"

    return at


def without_lines(layout: Layout, drop: Callable[[str], bool]) -> Layout:
    """``layout`` without its lines that ``drop`` says go (an e-stop since reset)."""
    return lambda width: "\n".join(ln for ln in layout(width).split("\n") if not drop(ln))
