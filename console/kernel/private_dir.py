"""The per-user runtime directory and files that never follow a symlink.

Sockets, the process registry and run logs live in ``$XDG_RUNTIME_DIR/haptable`` (a
systemd user's private tmpfs) or, without it, ``/tmp/haptable-<uid>``. The directory is
created 0700; an existing one must be a real directory (not a symlink) owned by this
user with no group or other permissions, else every command that needs it refuses in one
line with the fix. Files written in it, or in any shared directory, are opened with
``O_NOFOLLOW`` and created 0600, so a planted symlink can never redirect a write.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from console.core.errors import UserError
from console.files import paths


def runtime_dir() -> Path:
    """The checked private directory (created 0700 on first use)."""
    return ensure_private_dir(paths.runtime_dir())


def ensure_private_dir(d: Path) -> Path:
    """Create ``d`` 0700, or verify an existing one is ours and private. Raises ``UserError``."""
    return ensure_own_dir(d, forbidden_mode=0o077, what="the runtime directory")


def ensure_own_dir(
    d: Path,
    *,
    forbidden_mode: int,
    what: str,
    fix: str = "set XDG_RUNTIME_DIR to a directory of yours",
) -> Path:
    """Create ``d`` (0700, parents too) or check an existing one: a real directory (not a
    symlink) owned by this user, none of ``forbidden_mode``'s bits set (0o077: private;
    0o022: nobody else may write, as a socket's folder needs). ``UserError`` naming ``d``,
    ``what`` it is for and the fix otherwise."""
    try:
        d.mkdir(mode=0o700, parents=True, exist_ok=True)
        st = os.lstat(d)
    except FileExistsError:  # a file or a dangling symlink in the way
        st = os.lstat(d)
    except OSError as exc:
        raise UserError(f"{d}: cannot create {what}: {exc.strerror}; {fix}") from None
    if stat.S_ISLNK(st.st_mode) or not stat.S_ISDIR(st.st_mode):
        raise UserError(
            f"{d}: {what} is not a plain directory (a symlink or file; not a plain folder); "
            f"remove it (another user may have planted it) or {fix}"
        )
    if st.st_uid != os.getuid():
        raise UserError(
            f"{d}: {what} belongs to uid {st.st_uid}, not to you ({os.getuid()}); "
            f"remove it or {fix}"
        )
    if st.st_mode & forbidden_mode:
        mode = stat.S_IMODE(st.st_mode)
        cmd = "chmod 700" if forbidden_mode == 0o077 else "chmod go-w"
        raise UserError(
            f"{d}: {what} has mode {mode:03o} (a shared folder: others may replace what is "
            f"in it); run `{cmd} {d}` or {fix}"
        )
    return d


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie does not; another user's does)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except (OSError, IndexError):
        return True


def open_private(path: Path | str, *, append: bool = False) -> int:
    """Open ``path`` for writing without following a symlink; created 0600. A file
    descriptor; raises ``UserError`` when ``path`` is a symlink or cannot be opened."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_NOFOLLOW | getattr(os, "O_CLOEXEC", 0)
    flags |= os.O_APPEND if append else os.O_TRUNC
    try:
        return os.open(path, flags, 0o600)
    except OSError as exc:
        if os.path.islink(path):
            raise UserError(
                f"{path}: is a symlink; refusing to write through it (remove it)"
            ) from None
        raise UserError(f"{path}: cannot write: {exc.strerror}") from None


def write_private(path: Path | str, data: bytes | str) -> Path:
    """Write ``data`` to ``path`` (never through a symlink, created 0600)."""
    raw = data.encode() if isinstance(data, str) else data
    fd = open_private(path)
    with os.fdopen(fd, "wb") as f:
        f.write(raw)
    return Path(path)
