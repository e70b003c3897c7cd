"""Writing the signal library file without ever making it unreadable or losing an entry.

- ``dump(signals)``: the ``[signals]`` table as TOML. Every value TOML can hold is written
  back (strings, numbers, booleans, dates, arrays, inline tables), so an entry that does
  not validate is kept as it was, not dropped; keys that are not bare are quoted; control
  characters are escaped.
- ``write(path, signals)``: the text is read back before anything is replaced (it must
  parse and dump to the very same text, encode as UTF-8 and stay within what reading
  accepts: ``MAX_ENTRIES`` signals, ``MAX_LIBRARY_BYTES``), else nothing is written.
  A symlinked library is written through to its target (the link stays a link); the
  file's mode and owner are kept; a read-only file (no write bit) is refused, not
  replaced.
- ``locked(path)``: an exclusive lock beside the real file, opened so that a FIFO or a
  symlink put in its place refuses in one line instead of blocking.
"""

from __future__ import annotations

import contextlib
import datetime
import errno
import fcntl
import math
import os
import re
import stat
import tomllib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from console.core.errors import UserError
from console.files.atomic import write_text_atomic
from console.files.file_read import kind_of

#: what a library may weigh and hold: reading refuses more, so a write must too
MAX_LIBRARY_BYTES = 1 << 20
MAX_ENTRIES = 1000

HEADER = (
    "# HapTable signal library: named signals in the console's expression syntax.\n"
    "# Written by `haptable signals add` and the console's Signals screen; edits by hand\n"
    "# are kept (comments are not).\n"
)
_BARE = re.compile(r"[A-Za-z0-9_-]+")
_ESCAPES = {'"': '\\"', "\\": "\\\\", "\n": "\\n", "\t": "\\t", "\r": "\\r"}


def _string(s: str) -> str:
    return (
        '"'
        + "".join(
            _ESCAPES.get(c) or (f"\\u{ord(c):04x}" if ord(c) < 0x20 or ord(c) == 0x7F else c)
            for c in s
        )
        + '"'
    )


def _key(k: str) -> str:
    return k if _BARE.fullmatch(k) else _string(k)


def _value(v: Any) -> str:
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("nan" if v != v else "inf" if v > 0 else "-inf")
    if isinstance(v, (datetime.date, datetime.time)):  # datetime is a date
        return v.isoformat()
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"no TOML for {type(v).__name__}")


def dump(signals: dict[str, Any]) -> str:
    """The library file for the ``[signals]`` table ``signals`` (entries in its order)."""
    out = [HEADER.rstrip("\n")]
    plain = [(k, v) for k, v in signals.items() if not isinstance(v, dict)]
    if plain:  # entries that are not tables (kept as they were written)
        out += ["", "[signals]", *(f"{_key(k)} = {_value(v)}" for k, v in plain)]
    for name, table in signals.items():
        if isinstance(table, dict):
            out += ["", f"[signals.{_key(name)}]"]
            out += [f"{_key(k)} = {_value(v)}" for k, v in table.items()]
    return "\n".join(out) + "\n"


def _reads_back(text: str) -> str | None:
    """Why ``text`` would not read back as itself, or ``None``."""
    try:
        text.encode("utf-8")
        again = tomllib.loads(text)
        if set(again) - {"signals"}:
            return "a key outside [signals]"
        if dump(again.get("signals", {})) != text:
            return "it reads back differently"
    except (UnicodeError, ValueError, RecursionError, TypeError) as exc:
        return f"{type(exc).__name__}: {exc}"
    return None


def write_target(path: Path) -> Path:
    """The file a write of ``path`` replaces: ``path``, or the target of the symlink it is."""
    if not path.is_symlink():
        return path
    try:
        return Path(os.path.realpath(path, strict=True))
    except FileNotFoundError:  # a dangling link: the file it names is created
        real = Path(os.path.realpath(path))
        if not real.parent.is_dir():
            raise UserError(
                f"{path}: a symlink to {real}, whose folder does not exist; nothing was "
                "written; fix the link or remove it"
            ) from None
        return real
    except OSError as exc:
        why = "a symlink loop" if exc.errno == errno.ELOOP else exc.strerror or str(exc)
        raise UserError(f"{path}: {why}; nothing was written; remove the link") from None


def write(path: Path, signals: dict[str, Any]) -> None:
    """``signals`` as the library at ``path`` (see the module docstring)."""
    target = write_target(path)
    if len(signals) > MAX_ENTRIES:
        raise UserError(
            f"{path}: the library would hold {len(signals)} signals, more than the "
            f"{MAX_ENTRIES} it keeps; nothing was written; remove some first"
        )
    text = dump(signals)
    if len(text.encode("utf-8", "replace")) > MAX_LIBRARY_BYTES:
        raise UserError(
            f"{path}: the library would grow beyond {MAX_LIBRARY_BYTES / 2**20:g} MB; nothing was "
            "written; remove some signals first"
        )
    why = _reads_back(text)
    if why is not None:
        raise UserError(
            f"{path}: the library would not read back after this change ({why}); nothing "
            "was written; please report it"
        )
    mode = owner = None
    try:
        st = os.stat(target)
    except FileNotFoundError:
        st = None
    if st is not None:
        mode = stat.S_IMODE(st.st_mode)
        if not mode & 0o222:
            shown = f" (through {path})" if target != path else ""
            raise UserError(
                f"{target}{shown}: read-only (mode {mode:04o}); nothing was written; make it "
                f"writable (chmod u+w {target}) to change the library"
            )
        if (st.st_uid, st.st_gid) != (os.geteuid(), os.getegid()):
            owner = (st.st_uid, st.st_gid)
    try:
        write_text_atomic(target, text, mode=mode, owner=owner)
    except OSError as exc:
        raise UserError(f"{target}: cannot write: {exc.strerror or exc}") from None


@contextlib.contextmanager
def locked(path: Path) -> Iterator[None]:
    """Hold the library's write lock (a file beside the real library)."""
    target = write_target(path)
    lock = target.with_name(target.name + ".lock")
    with contextlib.suppress(FileNotFoundError):
        mode = os.lstat(lock).st_mode
        if not stat.S_ISREG(mode):  # a FIFO would block, a symlink lead elsewhere
            raise UserError(
                f"{lock}: {kind_of(mode)}, not a lock file; remove it (it only keeps two "
                "writers apart)"
            )
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        flags = os.O_WRONLY | os.O_CREAT | os.O_NONBLOCK | os.O_NOFOLLOW | os.O_CLOEXEC
        fd = os.open(lock, flags, 0o600)
    except OSError as exc:
        kind = "a symlink" if exc.errno == errno.ELOOP else exc.strerror or str(exc)
        raise UserError(
            f"{lock}: cannot open the library's lock file ({kind}); remove it (it only "
            "keeps two writers apart)"
        ) from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise UserError(
                f"{lock}: {kind_of(mode)}, not a lock file; remove it (it only keeps two "
                "writers apart)"
            )
        fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)  # closing releases the lock
