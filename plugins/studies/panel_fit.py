"""The Studies screen's protocol dropdown sized to the protocols' names: closed, as wide
as the longest within what the form's first row leaves; open, its list as wide as the
longest name within the screen (a name never wraps)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from textual.widgets import Input, Select

from console.plugin_api import UserError

from . import protocol as protocols
from .events import read_events
from .panel_text import next_id
from .store import RunFiles, participant_dir, progress

#: a compact Select's own columns beside the name: its padding and the "▼"
SELECT_EXTRA = 4
#: the open list's own columns: its border and each option's padding
LIST_EXTRA = 6
#: the rest of the form's first row at its widest: labels, participant, checkboxes, gaps
ROW_REST = 64
#: never narrower than this (the old fixed width)
MIN_W = 14


def protocol_width(names: list[str], screen_w: int) -> int:
    """Columns for the closed dropdown: the longest name and the Select's own, capped at
    what the row leaves on a ``screen_w``-column screen."""
    want = max([len(n) for n in names] or [0]) + SELECT_EXTRA
    return max(MIN_W, min(want, screen_w - ROW_REST))


def list_width(names: list[str], screen_w: int) -> int:
    """Columns for the open list: every name whole, within the screen."""
    want = max([len(n) for n in names] or [0]) + LIST_EXTRA
    return max(MIN_W, min(want, screen_w - 2))


def fit_protocols(pane: Any) -> None:
    """The dropdown and its list sized to the names at the screen's width now."""
    names, screen_w = protocols.available(), pane.app.size.width
    select = pane.query_one("#protocol", Select)
    select.styles.width = protocol_width(names, screen_w)
    select.query_one("SelectOverlay").styles.width = list_width(names, screen_w)


def mounted(pane: Any) -> None:
    """The pane is up: its dropdown sized to the names, then its idle status."""
    fit_protocols(pane)
    pane._idle()


def protocol_changed(pane: Any, name: str) -> None:
    """Another protocol chosen: the status says it (the last key's outcome, about the
    protocol before, is replaced) with what it needs, unless a run is going on."""
    if pane.running is not None:
        return
    field = pane.query_one("#participant", Input)
    pid = field.value.strip()
    out = Path(pane.query_one("#out", Input).value.strip() or ".").expanduser()
    stored = stored_progress(out, pid) if pid else None
    if stored is not None and stored[0] == stored[1]:  # this one is done: the next
        field.value = next_id(pid)
        said = f"{pid} has finished {name} ({stored[0]}/{stored[1]}): s starts {field.value}"
    elif stored is not None and stored[0]:
        said = f"protocol {name}: s resumes {pid} at trial {stored[0] + 1} of {stored[1]}"
    else:
        said = f"protocol {name} chosen: s starts it with {pid or 'a participant'}"
    pane.said = (said, "information")
    pane._idle()


def stored_progress(out: Path, pid: str) -> tuple[int, int] | None:
    """(trials done, trials) of ``pid``'s run in ``out``; None without one (or a folder
    that cannot be read: starting says why)."""
    try:
        files = RunFiles(participant_dir(out, pid))
        plan = json.loads(files.plan_path.read_text(encoding="utf-8"))
        st = progress(plan, read_events(files.trials_path) if files.trials_path.exists() else [])
    except (OSError, ValueError, KeyError, TypeError, UserError):
        return None
    return len(st.done), st.total
