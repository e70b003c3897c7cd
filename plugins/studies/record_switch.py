"""The Studies screen's "record trials" switch: what ``haptable study run ... --record``
sets for a run started on the screen (each trial into ``<participant>/recording/``, see
``trial_recording`` and ``adaptive_recording``). It starts as the profile's ``[recording]
study_trials`` and sits on the folder row, beside where the files go."""

from __future__ import annotations

from typing import Any

from textual.containers import Horizontal
from textual.widgets import Input, Label

from console.plugin_api.tui import PathInput, Tick

from .trial_recording import RECORD

__all__ = ["RECORD", "folder_row", "typed_field"]


def typed_field(value: str = "", **kw: Any) -> Input:
    """A field holding a path or typed work: the focus keeps its text (a key types into
    it, not over it all, as a focus selecting everything made it)."""
    return Input(value, compact=True, select_on_focus=False, **kw)


def folder_row(out: str, profile: Any) -> Horizontal:
    """The folder row: where the results go, and the record-trials switch."""
    return Horizontal(
        Label("folder", markup=False),
        # a path: too long for the field, it shows with … in its middle (never cut
        # against the switch beside it)
        PathInput(
            out, placeholder="where the results go", id="out", compact=True, select_on_focus=False
        ),
        Tick(
            "record trials",
            bool(profile.get("recording.study_trials")),
            id=RECORD,
            compact=True,
            tooltip="each trial into <participant>/recording/ (haptable study replay)",
        ),
        id="study-folder",
        classes="study-row",
    )
