"""Reading a small file the operator may have replaced by anything: checked for kind and
size before a byte is read.

``read_text_capped(path, what=..., fix=..., max_bytes=...)`` returns the file's text or
raises ONE-line ``UserError`` (or the ``error`` class given) naming the file and the fix:

- it must be a regular file: a FIFO would block the reader forever, a device such as
  ``/dev/zero`` never ends, a directory or a socket is no file at all. The kind is
  checked on the path (following symlinks) before it is opened, so opening has no side
  effect, then again on the open descriptor (opened non-blocking), so a swap between the
  two is caught;
- at most ``max_bytes``: the size is checked before reading and the read itself is
  bounded (a file growing meanwhile, or a ``/proc`` file claiming 0 bytes, cannot make it
  read more);
- UTF-8 (the line of the first bad byte is named).

``read_toml_capped`` parses the text as TOML with the same one-line errors (nesting too
deep, an integer beyond Python's digit limit). ``missing_ok``: a file that does not exist
(or a dangling symlink) reads as ``None``.
"""

from __future__ import annotations

import errno
import os
import stat
import tomllib
from pathlib import Path
from typing import Any

from console.core.errors import UserError

#: what a settings file may weigh unless the caller says otherwise
MAX_TEXT_BYTES = 1 << 20

_KINDS = (
    (stat.S_ISDIR, "a folder"),
    (stat.S_ISFIFO, "a FIFO (named pipe)"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISLNK, "a symlink"),
)


def _size(n: int) -> str:
    return f"{n / 2**20:.1f} MB" if n >= 2**20 else f"{n:,} bytes"


def kind_of(mode: int) -> str:
    """``a FIFO (named pipe)``, ``a folder`` ... for a ``st_mode`` that is not a regular file."""
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def check_regular(
    path: Path, *, what: str, fix: str, error: type[UserError] = UserError, missing_ok: bool = False
) -> os.stat_result | None:
    """The ``stat`` of ``path`` (symlinks followed) when it is a regular file; ``None``
    when it does not exist and ``missing_ok``; else one line."""
    try:
        st = os.stat(path)
    except FileNotFoundError:
        if missing_ok:
            return None
        raise error(f"{path}: no such file; {fix}") from None
    except OSError as exc:
        raise error(_os_problem(path, exc, what, fix)) from None
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{path}: {kind_of(st.st_mode)}, not a {what}; {fix}")
    return st


def _os_problem(path: Path, exc: OSError, what: str, fix: str) -> str:
    if exc.errno == errno.ELOOP:
        return f"{path}: a symlink loop, not a {what}; remove the link or point it at a file"
    return f"{path}: cannot read the {what} ({exc.strerror or exc}); {fix}"


def read_bytes_capped(
    path: str | os.PathLike,
    *,
    what: str,
    fix: str,
    max_bytes: int = MAX_TEXT_BYTES,
    error: type[UserError] = UserError,
    missing_ok: bool = False,
) -> bytes | None:
    """The bytes of a regular file of at most ``max_bytes`` (see the module docstring)."""
    p = Path(path)
    st = check_regular(p, what=what, fix=fix, error=error, missing_ok=missing_ok)
    if st is None:
        return None
    if st.st_size > max_bytes:
        raise error(
            f"{p}: {_size(st.st_size)} is too large for a {what} (at most {_size(max_bytes)}); "
            f"{fix}"
        )
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0)
    try:
        fd = os.open(p, flags)
    except FileNotFoundError:
        if missing_ok:
            return None
        raise error(f"{p}: no such file; {fix}") from None
    except OSError as exc:
        raise error(_os_problem(p, exc, what, fix)) from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):  # swapped after the check above
            raise error(f"{p}: {kind_of(mode)}, not a {what}; {fix}")
        chunks, total = [], 0
        while chunk := os.read(fd, min(1 << 16, max_bytes + 1 - total)):
            chunks.append(chunk)
            total += len(chunk)
            if total > max_bytes:
                raise error(f"{p}: more than {_size(max_bytes)}, too large for a {what}; {fix}")
    except OSError as exc:
        raise error(_os_problem(p, exc, what, fix)) from None
    finally:
        os.close(fd)
    return b"".join(chunks)


def read_text_capped(
    path: str | os.PathLike,
    *,
    what: str,
    fix: str,
    max_bytes: int = MAX_TEXT_BYTES,
    error: type[UserError] = UserError,
    missing_ok: bool = False,
) -> str | None:
    """The UTF-8 text of a regular file of at most ``max_bytes``."""
    data = read_bytes_capped(
        path, what=what, fix=fix, max_bytes=max_bytes, error=error, missing_ok=missing_ok
    )
    if data is None:
        return None
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data[: exc.start].count(b"\n") + 1
        raise error(
            f"{path}: not UTF-8 text (byte {data[exc.start]:#04x} on line {line}); save the "
            f"{what} as UTF-8"
        ) from None


def read_toml_capped(
    path: str | os.PathLike,
    *,
    what: str,
    fix: str,
    max_bytes: int = MAX_TEXT_BYTES,
    error: type[UserError] = UserError,
    missing_ok: bool = False,
) -> dict[str, Any] | None:
    """The TOML of a regular file of at most ``max_bytes``, parsed."""
    text = read_text_capped(
        path, what=what, fix=fix, max_bytes=max_bytes, error=error, missing_ok=missing_ok
    )
    return None if text is None else parse_toml_text(text, where=str(path), what=what, error=error)


def parse_toml_text(
    text: str,
    *,
    where: str,
    what: str,
    error: type[UserError] = UserError,
    levels: str = "a few levels",
) -> dict[str, Any]:
    """``text`` as TOML, or one line naming ``where``; ``levels``: how deep a ``what``
    nests (said when the text nests too deeply to read)."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{where}: not valid TOML: {exc}; correct the {what} by hand") from None
    except RecursionError:
        raise error(
            f"{where}: arrays or tables nested too deeply to read; a {what} needs {levels}"
        ) from None
    except ValueError as exc:  # an integer beyond Python's digit limit
        raise error(
            f"{where}: a value TOML allows but no setting can hold ({str(exc).split(';')[0]}); "
            "write it as a short number"
        ) from None
