"""Bounded reading of the studies' text files: protocols, ``plan.json``,
``participant.json`` and ``trials.jsonl``.

Nothing is read before the file is known to be a regular file of an allowed size
(``console.files.file_read``: a FIFO, a directory, a device such as ``/dev/zero`` is a
line, never a hang or a read until memory runs out), and no more than the limit is ever
read. Text and JSON are checked by the console's reader (``console.plugin_api``:
``decode``, ``parse_json``, ``read_json_lines``): every failure is one ``UserError``
naming the file, the line and the fix; ``trials.jsonl`` is read line by line, a line cut
short by a crash skipped wherever a later append put it.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

from console.plugin_api import (
    UserError,
    decode,
    parse_json,
    read_bytes_capped,
    read_json_lines,
)

#: limits of each kind of file (a plan of 100,000 trials is about 40 MB)
MAX_PROTOCOL_BYTES = 1 * 2**20
MAX_JSON_BYTES = 64 * 2**20
MAX_JSONL_BYTES = 256 * 2**20


def read_bytes(path: Path, *, what: str, fix: str, limit: int) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes (empty allowed): the
    console's capped reader (kind checked on the path and on the open descriptor, the
    read itself bounded)."""
    data = read_bytes_capped(path, what=what, fix=fix, max_bytes=limit)
    assert data is not None  # not missing_ok: a missing file is a UserError
    return data


def read_json(path: Path, *, what: str, fix: str, limit: int = MAX_JSON_BYTES) -> Any:
    """A JSON file (``what`` names it in messages, ``fix`` ends each)."""
    data = read_bytes(path, what=what, fix=fix, limit=limit)
    if not data.strip():
        raise UserError(f"{path}: empty file, not a {what}; {fix}")
    return parse_json(decode(data, str(path), fix), str(path), fix)


def jsonl_lines(
    path: Path, *, what: str, fix: str, file_fix: str, limit: int = MAX_JSONL_BYTES
) -> Iterator[tuple[int, Any]]:
    """``(line number, event)`` of ``trials.jsonl`` (``console.plugin_api.read_json_lines``:
    a torn line ``(n, None)``, any other bad line one ``UserError``)."""
    return read_json_lines(path, what=what, fix=fix, file_fix=file_fix, limit=limit, noun="event")
