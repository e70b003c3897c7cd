"""Fields that hold a path. ``PathInput``: a path longer than its field shows, while
the field has no focus, with ``…`` in its middle: its start and its last names visible,
never cut at the field's edge (the Studies folder read ``.../studies/jnd_am`` against the
next control at 80 columns); with the focus it is the path as typed. ``recording_field``:
the field ``o`` opens on the Camera and Scope screens: a recording's path, with a label
on its border saying what to type (its placeholder alone read like a value), and its
keys on the border's other side (a hint cut at 80 columns lost them). Every field that
takes a path is a ``PathField``: it types every key, ``?`` too (a path may hold one; the
recording field opened the help on it while the TUIO target typed it)."""

from __future__ import annotations

from rich.cells import cell_len
from rich.text import Text
from textual.strip import Strip
from textual.widgets import Input

from console.tui.focus_keys import name_field
from console.tui.narrow import TypesEveryKey

ELLIPSIS = "…"


def middle_ellipsis(path: str, width: int) -> str:
    """``path`` in at most ``width`` cells: whole when it fits, else its start, ``…``,
    and its end from a ``/`` on (the end, where the names that tell paths apart are,
    gets up to two thirds; the last name whole when it fits)."""
    if cell_len(path) <= width:
        return path
    if width <= 1:
        return ELLIPSIS[:width]
    end = path[len(path) - (2 * (width - 1)) // 3 :] if width > 2 else ""
    name = path[path.rfind("/") :] if "/" in path else ""
    if "/" in end[:-1]:  # it starts with a whole name
        end = end[end.index("/") :]
    elif name and len(end) < len(name) <= width - 2:  # the file's name whole, if it fits
        end = name
    return f"{path[: width - 1 - len(end)]}{ELLIPSIS}{end}"


def whole_names(path: str, width: int) -> str | None:
    """``path`` in at most ``width`` cells cut only between its names: whole when it fits,
    else its first names and its last one whole with ``…`` for those between
    (``/tmp/…/demo-8098-flow-1.json``); None when its last name alone does not fit (a
    caller then gives it a line of its own). ``middle_ellipsis`` cuts inside names."""
    if cell_len(path) <= width:
        return path
    head, sep, name = path.rpartition("/")
    if not sep or cell_len(name) + 2 > width:
        return None
    kept = ""
    for part in head.split("/"):
        longer = f"{kept}{part}/"
        if cell_len(longer) + cell_len(ELLIPSIS) + 1 + cell_len(name) > width:
            break
        kept = longer
    return f"{kept}{ELLIPSIS}/{name}"


class PathField(TypesEveryKey, Input):
    """An ``Input`` that takes a path or an address: every key typed, ``?`` included (the
    footer then promises no key: ``console.tui.narrow.TypesEveryKey``)."""


class PathInput(PathField):
    """An ``Input`` holding a path: without the focus a path too long for it shows with
    ``…`` in its middle (``middle_ellipsis``); with the focus, as typed, to edit."""

    def render_line(self, y: int) -> Strip:
        width = self.scrollable_content_region.width
        if y != 0 or self.has_focus or not self.value or cell_len(self.value) <= width:
            return super().render_line(y)
        shown = Text(middle_ellipsis(self.value, width), end="", no_wrap=True)
        strip = Strip(self.app.console.render(shown, self.app.console_options.update_width(width)))
        return strip.extend_cell_length(width + 1).crop(0, width + 1).apply_style(self.rich_style)

    def _on_blur(self, event) -> None:
        super()._on_blur(event)
        self.refresh()  # the shortened path again


#: the field's label: what it takes (whole on its border in the Camera screen's side
#: panel at 80 columns)
RECORDING_LABEL = "recording: a .h5 file's path"
#: the hint inside it while it is empty: where the console writes such a file (the
#: Studies screen's "record trials" switch); within the field at 80 columns
RECORDING_HINT = "e.g. <study folder>/P01/recording/trial_0000.h5 (Studies: record trials)"
#: the field's keys, on its lower border
RECORDING_KEYS = "Enter opens  Esc back"


def recording_field(widget_id: str, hint: str = RECORDING_HINT) -> PathField:
    """A hidden path field labelled ``RECORDING_LABEL`` (``o`` shows it), ``hint`` in it
    while it is empty (a narrow field says ``RECORDING_HINT`` on its screen's status
    line instead: cut in the field, it read ``e.g. <study``); focusing it selects
    nothing (a typed key would replace the path)."""
    box = PathField(placeholder=hint, id=widget_id, select_on_focus=False)
    box.border_title = RECORDING_LABEL
    box.border_subtitle = RECORDING_KEYS
    box.display = False
    return name_field(box, "recording", enter="open", escape="back")  # as its border says
