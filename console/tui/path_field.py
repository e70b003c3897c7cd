"""The field ``o`` opens on the Camera and Scope screens: a recording's path, with a
label on its border saying what to type (its placeholder alone read like a value)."""

from __future__ import annotations

from textual.widgets import Input

#: the field's label: what it takes, and where such a file comes from
RECORDING_LABEL = "recording to show: a .h5 file's path"
#: the hint inside it while it is empty
RECORDING_HINT = "e.g. ~/runs/flow.h5 (haptable demo ... --record FILE); Enter opens, Esc: back"


def recording_field(widget_id: str) -> Input:
    """A hidden path field labelled ``RECORDING_LABEL`` (``o`` shows it)."""
    box = Input(placeholder=RECORDING_HINT, id=widget_id)
    box.border_title = RECORDING_LABEL
    box.display = False
    return box
