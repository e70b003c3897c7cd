"""Bounded reading of the studies' text files: protocols, ``plan.json``,
``participant.json`` and ``trials.jsonl``.

Nothing is read before the file is known to be a regular file of an allowed size
(``console.files.file_read``: a FIFO, a directory, a device such as ``/dev/zero`` is a line,
never a hang or a read until memory runs out), and no more than the limit is ever read. Text must be UTF-8 (a bad byte is named with its line); JSON must parse, without
a key twice in an object, nesting at most ``MAX_DEPTH`` deep and no integer beyond
Python's digit limit: every failure is one ``UserError`` naming the file, the line and
the fix.

``trials.jsonl`` is read line by line (``jsonl_lines``): a line cut short by a crash (the
runner's append torn mid-write, perhaps with the zeros a file system leaves) is a crash's
trace and is skipped, wherever a later append put it; any other line that is not a JSON
object is an error naming its line.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from console.plugin_api import UserError, json_depth, read_bytes_capped

#: limits of each kind of file (a plan of 100,000 trials is about 40 MB)
MAX_PROTOCOL_BYTES = 1 * 2**20
MAX_JSON_BYTES = 64 * 2**20
MAX_JSONL_BYTES = 256 * 2**20
MAX_DEPTH = 32
#: what a torn number or literal can leave at the end of a line
_TORN_TAIL = re.compile(
    r"\.|[eE][+-]?|-|-?I(n(f(i(n(i(ty?)?)?)?)?)?)?|t(r(ue?)?)?|f(a(l(se?)?)?)?|n(u(ll?)?)?|Na?"
)


def read_bytes(path: Path, *, what: str, fix: str, limit: int) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes (empty allowed): the
    console's capped reader (kind checked on the path and on the open descriptor, the
    read itself bounded)."""
    data = read_bytes_capped(path, what=what, fix=fix, max_bytes=limit)
    assert data is not None  # not missing_ok: a missing file is a UserError
    return data


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


def _no_twice(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in pairs:
        if k in out:
            raise _Twice(k)
        out[k] = v
    return out


class _Twice(ValueError):
    pass


def parse_json(text: str, where: str, fix: str, *, depth: bool = True) -> Any:
    """A JSON value; every way it can fail is one line (``depth``: check the nesting
    limit too; a line of ``trials.jsonl`` is checked key by key instead)."""
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


def read_json(path: Path, *, what: str, fix: str, limit: int = MAX_JSON_BYTES) -> Any:
    """A JSON file (``what`` names it in messages, ``fix`` ends each)."""
    data = read_bytes(path, what=what, fix=fix, limit=limit)
    if not data.strip():
        raise UserError(f"{path}: empty file, not a {what}; {fix}")
    return parse_json(decode(data, str(path), fix), str(path), fix)


def torn(raw: bytes) -> bool:
    """Whether a line is what a crash leaves of the runner's append: a cut-short JSON
    object (a prefix of one, in ASCII as the runner writes), perhaps followed by the
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


def jsonl_lines(
    path: Path, *, what: str, fix: str, file_fix: str, limit: int = MAX_JSONL_BYTES
) -> Iterator[tuple[int, Any]]:
    """``(line number, object)`` of each line of a JSON-lines file (missing: none); a torn
    line yields ``(n, None)``; any other line not a JSON object is a ``UserError`` ending
    in ``fix`` (a file that cannot be read at all: ``file_fix``)."""
    p = Path(path)
    if not p.exists() and not p.is_symlink():
        return
    data = read_bytes(p, what=what, fix=file_fix, limit=limit)
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
            raise UserError(f"{where}: {kind[:60]}, not an event (a JSON object); {fix}")
        yield n, obj
