"""The knob task's trial log: one JSON object per finished trial, appended and made
durable before the next trial starts (``console.plugin_api.append_json_line``: flush,
fsync, a torn last line closed first), and read back line by line (``read_trials``).

Reading is bounded (a regular file of at most ``MAX_LOG_BYTES``, never a FIFO or a
device) and checked: a line cut short by a crash (a prefix of a JSON object, perhaps
followed by the zeros a file system leaves) is skipped wherever a later append put it;
any other line that is not a JSON object is one ``UserError`` naming the file and the
line.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import Any

from console.plugin_api import UserError, read_bytes_capped

#: a log of 100,000 trials is about 60 MB
MAX_LOG_BYTES = 256 * 2**20
FIX = (
    "the trial log is damaged: move it aside (a new run starts a new log with --log) or "
    "delete that line"
)
#: what a cut can leave where the decoder stopped: an open string (perhaps inside an
#: escape), a number, a literal, or nothing (the decoder wanted more)
_TORN_TAIL = re.compile(
    r'"(?:[^"\\]|\\.)*(?:\\(?:u[0-9a-fA-F]{0,3})?)?'
    r"|-?\d*\.?\d*(?:[eE][+-]?\d*)?|t(r(ue?)?)?|f(a(l(se?)?)?)?|n(u(ll?)?)?"
    r"|Na?|-?I(n(f(i(n(i(ty?)?)?)?)?)?)?"
)


def torn(text: str, exc: json.JSONDecodeError) -> bool:
    """Whether a line that does not parse is what a crash leaves of an append: an ASCII
    prefix of a JSON object, cut where the decoder stopped."""
    return (
        text.isascii()
        and text.lstrip().startswith("{")
        and _TORN_TAIL.fullmatch(text[exc.pos :]) is not None
    )


def read_trials(path: str | Path) -> list[dict[str, Any]]:
    """The finished trials of a log, in order (a missing log: none)."""
    p = Path(path)
    if not p.exists() and not p.is_symlink():
        return []
    data = read_bytes_capped(p, what="knob trial log", fix=FIX, max_bytes=MAX_LOG_BYTES)
    out = []
    for n, raw in enumerate((data or b"").split(b"\n"), 1):
        body = raw.rstrip(b"\0")
        if not body.strip():
            continue  # an empty line, or the zeros of a crash
        where = f"{p}: line {n}"
        try:
            text = body.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise UserError(f"{where}: byte {exc.start + 1} is not UTF-8 text; {FIX}") from None
        try:
            obj = json.loads(text)
        except json.JSONDecodeError as exc:
            if torn(text, exc):
                continue
            raise UserError(
                f"{where}: not valid JSON ({exc.msg}, column {exc.colno}); {FIX}"
            ) from None
        except (RecursionError, ValueError) as exc:
            raise UserError(f"{where}: not valid JSON ({str(exc)[:60]}); {FIX}") from None
        if not isinstance(obj, dict):
            kind = "a JSON list" if isinstance(obj, list) else f"the value {json.dumps(obj)[:40]}"
            raise UserError(f"{where}: {kind}, not a trial (a JSON object); {FIX}")
        out.append(obj)
    return out
