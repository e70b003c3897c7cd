"""What the Studies screen works out beside its widgets: a protocol's default results
folder, the next participant's id, a trial in words, a text clipped to a column."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from console.plugin_api import data_dir


def default_out(study: str = "") -> Path:
    """A protocol's default results folder: ``<data dir>/studies/<protocol>``."""
    return data_dir("studies", study) if study else data_dir("studies")


def next_id(pid: str) -> str:
    """The next participant's id (``P01`` -> ``P02``; an id without a number: itself)."""
    m = re.match(r"^(.*?)(\d+)$", pid)
    if not m:
        return pid
    return f"{m.group(1)}{int(m.group(2)) + 1:0{len(m.group(2))}d}"


def trial_text(t: dict[str, Any]) -> str:
    """A trial as the experimenter reads it: phase, place, direction or condition."""
    place = t.get("region") or (f"pair {t['pair']}" if t.get("pair") else "")
    what = t.get("direction") or t.get("condition") or ""
    if t.get("stimulus", {}).get("task") == "knob":
        s = t["stimulus"]
        what = f"{s['condition']} {s['sectors']} sectors {s['distance_deg']:g} deg"
    hand = f" ({t['hand']} hand)" if t.get("hand") else ""
    return " ".join(x for x in (t.get("phase", ""), place, what) if x) + hand


def clip(text: str, width: int) -> str:
    """``text`` within ``width`` columns, ending in ``…`` when cut."""
    return text if len(text) <= width else text[: width - 1].rstrip() + "…"


def same_folder(a: Path, b: Path) -> bool:
    """The same folder (as typed, or resolved)."""
    try:
        return Path(a).expanduser().resolve() == Path(b).expanduser().resolve()
    except OSError:
        return Path(a) == Path(b)


#: the participant's number fields: (label, lowest, highest, whole numbers only)
NUMBER_FIELDS = {
    "age": ("age", 1, 120, True),
    "hand_width_cm": ("hand width cm", 3, 30, False),
    "hand_length_cm": ("hand length cm", 5, 40, False),
}


def field_refusal(field: str, value: str) -> str:
    """Why ``value`` in the participant's number ``field`` is refused ('' when it is
    empty or fits), one line naming the field and what it takes."""
    if field not in NUMBER_FIELDS or not value.strip():
        return ""
    label, lo, hi, whole = NUMBER_FIELDS[field]
    try:
        x = float(value)
    except ValueError:
        x = float("nan")
    if not lo <= x <= hi or (whole and x != int(x)):
        what = "whole years" if whole else "a number"
        return f"{label} = {value.strip()!r}: give {what} from {lo} to {hi}"
    return ""
