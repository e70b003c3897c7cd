"""Durable writes: a whole file replaced so that a reader sees the old file or the new
one, never a part (``write_text_atomic``); a JSON line appended and on disk before the
call returns (``append_json_line``)."""

from __future__ import annotations

import contextlib
import json
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any


def write_text_atomic(
    path: Path, text: str, *, mode: int | None = None, owner: tuple[int, int] | None = None
) -> None:
    """``text`` to ``path`` through a temporary file in the same folder (fsynced, renamed
    over it, the folder fsynced so the rename survives a power cut); the temporary file
    is gone whatever happens. ``OSError`` as raised.

    The new file is 0600 unless ``mode`` is given, owned by this process unless ``owner``
    (uid, gid) is: both are set before the rename, so the file never shows another mode
    (pass the old file's to keep them)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            if owner is not None:
                os.fchown(f.fileno(), *owner)
            if mode is not None:
                os.fchmod(f.fileno(), mode)
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    fsync_dir(path.parent)


def append_json_line(path: str | os.PathLike, record: Mapping[str, Any]) -> None:
    """Append ``record`` as one JSON line (keys sorted) and make it durable (flush +
    fsync) before returning; a torn last line (a crash mid-write) gets a newline first so
    it cannot swallow this one. ``OSError`` as raised."""
    line = json.dumps(record, sort_keys=True) + "\n"
    with open(path, "ab+") as f:
        if f.tell() > 0:
            f.seek(-1, os.SEEK_END)
            if f.read(1) != b"\n":
                line = "\n" + line
        f.write(line.encode("utf-8"))
        f.flush()
        os.fsync(f.fileno())


def fsync_dir(folder: Path) -> None:
    """Make a folder's entries (a new or renamed file) durable; best effort."""
    with contextlib.suppress(OSError):
        fd = os.open(folder, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
