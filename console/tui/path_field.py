"""The field ``o`` opens on the Camera and Scope screens: a recording's path, with a
label on its border saying what to type (its placeholder alone read like a value), and
its keys on the border's other side (a hint cut at 80 columns lost them)."""

from __future__ import annotations

from textual.widgets import Input

#: the field's label: what it takes (whole on its border in the Camera screen's side
#: panel at 80 columns)
RECORDING_LABEL = "recording: a .h5 file's path"
#: the hint inside it while it is empty: where the console writes such a file (the
#: Studies screen's "record trials" switch); within the field at 80 columns
RECORDING_HINT = "e.g. <study folder>/P01/recording/trial_0000.h5 (Studies: record trials)"
#: the field's keys, on its lower border
RECORDING_KEYS = "Enter opens  Esc back"


def recording_field(widget_id: str, hint: str = RECORDING_HINT) -> Input:
    """A hidden path field labelled ``RECORDING_LABEL`` (``o`` shows it), ``hint`` in it
    while it is empty (a narrow field says ``RECORDING_HINT`` on its screen's status
    line instead: cut in the field, it read ``e.g. <study``); focusing it selects
    nothing (a typed key would replace the path)."""
    box = Input(placeholder=hint, id=widget_id, select_on_focus=False)
    box.border_title = RECORDING_LABEL
    box.border_subtitle = RECORDING_KEYS
    box.display = False
    return box
