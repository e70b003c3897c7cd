"""The knob task's trial log: one JSON object per finished trial, appended and made
durable before the next trial starts (``console.plugin_api.append_json_line``: flush,
fsync, a torn last line closed first), and read back line by line (``read_trials``,
with its reader ``console.plugin_api.read_json_lines``: bounded, a line cut short by a
crash skipped wherever a later append put it, any other bad line one ``UserError``
naming the file and the line).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from console.plugin_api import read_json_lines

#: a log of 100,000 trials is about 60 MB
MAX_LOG_BYTES = 256 * 2**20
FIX = (
    "the trial log is damaged: move it aside (a new run starts a new log with --log) or "
    "delete that line"
)


def read_trials(path: str | Path) -> list[dict[str, Any]]:
    """The finished trials of a log, in order (a missing log: none; a torn line is
    skipped: ``console.plugin_api.read_json_lines``)."""
    lines = read_json_lines(path, what="knob trial log", fix=FIX, limit=MAX_LOG_BYTES, noun="trial")
    return [obj for _, obj in lines if obj is not None]
