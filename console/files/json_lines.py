"""JSON text and JSON-lines logs read back, every failure one line.

The writer is ``console.files.atomic.append_json_line`` (one object per line, flushed
and fsynced, a torn last line closed first); this is its reader. ``read_json_lines``
yields ``(line number, object)``: a line cut short by a crash (a prefix of a JSON
object, perhaps followed by the zeros a file system leaves, or those zeros alone) is a
crash's trace, yielded as ``(n, None)`` wherever a later append put it; any other line
that is not a JSON object is one ``UserError`` naming the file, the line and the fix.
The file is read bounded (``console.files.file_read``: a regular file of at most the
limit, never a FIFO or a device). ``decode`` and ``parse_json`` are the same checks
for a whole JSON file: UTF-8 named by line, no key twice in an object, nesting at most
``MAX_DEPTH`` deep, no integer beyond Python's digit limit.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from console.core.errors import UserError
from console.files.file_read import read_bytes_capped
from console.files.npz_safe import json_depth

#: the deepest nesting a JSON file may have
MAX_DEPTH = 32
#: a log of 100,000 trials is about 60 MB
MAX_JSONL_BYTES = 256 * 2**20
#: what a torn number or literal can leave at the end of a line
_TORN_TAIL = re.compile(
    r"\.|[eE][+-]?|-|-?I(n(f(i(n(i(ty?)?)?)?)?)?)?|t(r(ue?)?)?|f(a(l(se?)?)?)?|n(u(ll?)?)?|Na?"
)


def decode(data: bytes, where: str, fix: str, *, line: int | None = None) -> str:
    """UTF-8 text; a bad byte is named with its line (``line``: the number of the line
    ``data`` is, for a file read line by line)."""
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        start = data.rfind(b"\n", 0, exc.start) + 1
        n = line if line is not None else data.count(b"\n", 0, exc.start) + 1
        raise UserError(
            f"{where}: line {n}: byte 0x{data[exc.start]:02x} (byte {exc.start - start + 1} of "
            f"the line) is not UTF-8 text: the file is damaged; {fix}"
        ) from None


class _Twice(ValueError):
    pass


def _no_twice(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise _Twice(k)
        out[k] = v
    return out


def parse_json(text: str, where: str, fix: str, *, depth: bool = True) -> Any:
    """A JSON value; every way it can fail is one line (``depth``: check the nesting
    limit too; a line of a log is checked key by key instead)."""
    try:
        obj = json.loads(text, object_pairs_hook=_no_twice)
    except _Twice as exc:
        raise UserError(
            f"{where}: key {exc.args[0]!r} appears twice in one object; {fix}"
        ) from None
    except RecursionError:
        raise UserError(f"{where}: nested deeper than {MAX_DEPTH} levels; {fix}") from None
    except json.JSONDecodeError as exc:
        raise UserError(f"{where}: not valid JSON ({exc}); {fix}") from None
    except ValueError as exc:  # an integer beyond the digit limit
        raise UserError(f"{where}: not valid JSON ({str(exc).split(';')[0]}); {fix}") from None
    if depth and json_depth(obj) > MAX_DEPTH:
        raise UserError(f"{where}: nested deeper than {MAX_DEPTH} levels; {fix}")
    return obj


def torn(raw: bytes) -> bool:
    """Whether a line is what a crash leaves of an append: a cut-short JSON object (a
    prefix of one, in ASCII as ``append_json_line`` writes), perhaps followed by the
    zeros of a file system's crash, or those zeros alone."""
    body = raw.rstrip(b"\0")
    if not body.strip():
        return raw != body
    if not body.isascii() or not body.lstrip().startswith(b"{"):
        return False
    text = body.decode("ascii")
    for _ in range(8):  # each round closes one string the cut left open
        try:
            json.loads(text)
        except json.JSONDecodeError as exc:
            if exc.pos >= len(text):
                return True  # the decoder wanted more: a prefix
            if exc.msg.startswith(("Unterminated string", "Invalid \\uXXXX")):
                text = re.sub(r"\\(u[0-9a-fA-F]{0,3})?$", "", text) + '"'
                continue
            return _TORN_TAIL.fullmatch(text[exc.pos :]) is not None
        except (RecursionError, ValueError):
            return False
        return False  # a whole object is not torn (the caller has parsed it)
    return False


def read_json_lines(
    path: str | Path,
    *,
    what: str,
    fix: str,
    file_fix: str | None = None,
    limit: int = MAX_JSONL_BYTES,
    noun: str = "record",
) -> Iterator[tuple[int, Any]]:
    """``(line number, object)`` of each line of a JSON-lines file (missing: none); a torn
    line yields ``(n, None)``; any other line not a JSON object is a ``UserError`` ending
    in ``fix`` (a file that cannot be read at all: ``file_fix``, else ``fix``); ``what``
    names the file and ``noun`` a line of it in messages."""
    p = Path(path)
    if not p.exists() and not p.is_symlink():
        return
    data = read_bytes_capped(p, what=what, fix=file_fix or fix, max_bytes=limit) or b""
    for n, raw in enumerate(data.split(b"\n"), 1):
        if not raw.strip():
            if raw:
                yield n, None  # zeros: a crash's trace
            continue
        where = f"{p}: line {n}"
        try:
            obj = parse_json(decode(raw, str(p), fix, line=n), where, fix, depth=False)
        except UserError:
            if torn(raw):
                yield n, None
                continue
            raise
        if not isinstance(obj, dict):
            kind = "a JSON list" if isinstance(obj, list) else f"the value {json.dumps(obj)}"
            raise UserError(f"{where}: {kind[:60]}, not {_a(noun)} (a JSON object); {fix}")
        yield n, obj


def _a(noun: str) -> str:
    return f"an {noun}" if noun[:1] in "aeiou" else f"a {noun}"
