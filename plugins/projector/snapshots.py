"""Where a ``snapshot`` request over the link may write: only inside the snapshot folder.

The folder is ``[projector] snapshot_dir`` (or ``--snapshot-dir``), by default
``snapshots`` in the private per-user runtime directory. A request names a file in it
(relative) or an absolute path inside it; anything resolving outside, a symlink, or a
name that is not a file name is refused. Files are written 0600 without following a
symlink. (``haptable projector --screenshot PNG`` is a path the user typed and is not
restricted.)
"""

from __future__ import annotations

import os
from pathlib import Path

from console.plugin_api import UserError
from console.plugin_api.runtime import ensure_private_dir, runtime_dir, write_private


def snapshot_dir(configured: str | os.PathLike | None = None) -> Path:
    """The snapshot folder (created 0700 when missing), resolved."""
    if not configured:
        return ensure_private_dir(runtime_dir() / "snapshots").resolve()
    d = Path(configured).expanduser()
    try:
        d.mkdir(mode=0o700, parents=True, exist_ok=True)
    except OSError as e:
        raise UserError(
            f"snapshot_dir {d}: cannot create it ({e.strerror}); set [projector] snapshot_dir "
            "to a folder of yours"
        ) from None
    if not d.is_dir():
        raise UserError(f"snapshot_dir {d}: not a folder; set [projector] snapshot_dir to one")
    return d.resolve()


def snapshot_target(base: Path, request: str) -> Path:
    """The file ``request`` names inside ``base``; ``UserError`` (one line) otherwise."""
    if not request or "\0" in request:
        raise UserError(f"snapshot {request!r}: not a file name; name a PNG in {base}")
    p = Path(request)
    p = p if p.is_absolute() else base / p
    if p.name in ("", ".", ".."):
        raise UserError(f"snapshot {request!r}: not a file name; name a PNG in {base}")
    parent = Path(os.path.realpath(p.parent))
    if parent != base and base not in parent.parents:
        raise UserError(
            f"snapshot {request!r}: outside the snapshot folder {base}; "
            "name a file inside it (or set [projector] snapshot_dir)"
        )
    target = parent / p.name
    if target.is_symlink():
        raise UserError(f"snapshot {request!r}: is a symlink; refusing to write through it")
    return target


def write_snapshot(path: Path, rgb) -> None:
    """Save an RGB frame as PNG at ``path`` (0600, never through a symlink)."""
    import cv2
    import numpy as np

    ok, png = cv2.imencode(".png", np.ascontiguousarray(rgb[:, :, ::-1]))
    if not ok:
        raise UserError(f"snapshot {path}: cannot encode the frame as PNG")
    write_private(path, png.tobytes())
