"""The projector link's wire format, checked strictly on both ends.

Messages are single lines of JSON objects, at most ``MAX_LINE_BYTES`` long (the largest
real scene state is about 2 KB). A line is refused (``ProtocolError``) when it is too long,
not UTF-8, not JSON, not an object, nested deeper than ``MAX_DEPTH``, holds a non-finite
number (``NaN``, ``Infinity``, ``1e400``) or an integer beyond 64 bits, has an unknown
``type`` or a known field of the wrong type. Nesting is measured before parsing, so no
line can make the parser recurse deeply. Either end answers a refused line by dropping
the connection.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any

MAX_LINE_BYTES = 1 << 20
MAX_DEPTH = 32
MAX_INT = 1 << 63

NUM = (int, float)
OPT_STR = (str, type(None))

#: Known messages and the types of their fields (``None`` in a tuple: may be null).
#: ``required`` fields must be present; the others are checked when present.
TO_PROJECTOR: dict[str, dict[str, Any]] = {
    "hello": {"role": str, "pid": int, "protocol": int},
    "state": {"seq": int, "scene": OPT_STR, "state": dict, "t_send_s": NUM},
    "heartbeat": {"t_s": NUM},
    "quit": {},
    "snapshot": {"path": str},
}
TO_CONSOLE: dict[str, dict[str, Any]] = {
    "hello": {
        "role": str,
        "pid": int,
        "protocol": int,
        "scene": OPT_STR,
        "size_px": list,
        "headless": bool,
    },
    "ack": {"seq": int, "t_recv_s": NUM},
    "drawn": {"seq": int, "t_drawn_s": NUM, "scene": OPT_STR},
    "heartbeat": {"t_s": NUM, "fps": NUM, "frames": int, "scene": OPT_STR},
    "snapshot_done": {"path": str, "file": str},
    "error": {"message": str, "path": str},
}
REQUIRED = {"state": ("seq", "state"), "snapshot": ("path",), "ack": ("seq",), "drawn": ("seq",)}


class ProtocolError(ValueError):
    """A line or message the link does not accept (the connection is then dropped)."""


def encode(msg: dict) -> bytes:
    """One message as a line of JSON (UTF-8, no embedded newlines)."""
    return json.dumps(msg, separators=(",", ":"), allow_nan=False).encode() + b"\n"


_STRINGS = re.compile(r'"[^"\\]*(?:\\.[^"\\]*)*"', re.S)
_BRACKETS = re.compile(r"[\[\]{}]")


def nesting_depth(text: str) -> int:
    """How deep ``[``/``{`` nest in JSON ``text`` (brackets inside strings ignored)."""
    bare = _STRINGS.sub("", text)
    if bare.count("[") + bare.count("{") <= MAX_DEPTH:
        return bare.count("[") + bare.count("{")  # an upper bound, within the limit
    depth = deepest = 0
    for b in _BRACKETS.findall(bare):
        depth += 1 if b in "[{" else -1
        deepest = max(deepest, depth)
    return deepest


def _no_constant(name: str) -> Any:
    raise ProtocolError(f"non-finite number {name}")


def _finite(text: str) -> float:
    v = float(text)
    if not math.isfinite(v):
        raise ProtocolError(f"non-finite number {text[:20]}")
    return v


def _bounded(text: str) -> int:
    v = int(text)
    if not -MAX_INT <= v < MAX_INT:
        raise ProtocolError(f"integer {text[:20]}... beyond 64 bits")
    return v


def decode(line: bytes, schema: dict[str, dict[str, Any]]) -> dict:
    """One line (without its newline) as a checked message, or ``ProtocolError``."""
    if len(line) > MAX_LINE_BYTES:
        raise ProtocolError(f"a line of {len(line)} bytes (at most {MAX_LINE_BYTES})")
    try:
        text = line.decode("utf-8")
    except UnicodeDecodeError:
        raise ProtocolError("a line that is not UTF-8") from None
    if nesting_depth(text) > MAX_DEPTH:
        raise ProtocolError(f"JSON nested deeper than {MAX_DEPTH} levels")
    try:
        msg = json.loads(text, parse_constant=_no_constant, parse_float=_finite, parse_int=_bounded)
    except ProtocolError:
        raise
    except (ValueError, RecursionError) as e:
        raise ProtocolError(f"not JSON ({str(e)[:80]})") from None
    return check(msg, schema)


def check(msg: Any, schema: dict[str, dict[str, Any]]) -> dict:
    """``msg`` if it is a known message with fields of the right types."""
    if not isinstance(msg, dict):
        raise ProtocolError(f"a JSON {type(msg).__name__}, not an object")
    kind = msg.get("type")
    if not isinstance(kind, str) or kind not in schema:
        raise ProtocolError(f"unknown message type {str(kind)[:40]!r}")
    fields = schema[kind]
    for name in REQUIRED.get(kind, ()):
        if name not in msg:
            raise ProtocolError(f"{kind} without {name!r}")
    for name, want in fields.items():
        if name not in msg:
            continue
        v = msg[name]
        wants = want if isinstance(want, tuple) else (want,)
        no_bool = isinstance(v, bool) and bool not in wants  # JSON true is no number
        if no_bool or not isinstance(v, wants):
            raise ProtocolError(f"{kind}.{name} is a {type(v).__name__}")
    if "seq" in fields and "seq" in msg and msg["seq"] < 0:
        raise ProtocolError(f"{kind}.seq is negative")
    return msg


class LineBuffer:
    """Splits a byte stream into lines; a line longer than the bound is an error at once."""

    def __init__(self, max_line_bytes: int = MAX_LINE_BYTES) -> None:
        self.buf = bytearray()
        self.max = max_line_bytes

    def feed(self, data: bytes) -> list[bytes]:
        """The complete non-blank lines so far (``ProtocolError`` on an over-long one)."""
        self.buf += data
        lines = []
        start = 0
        while True:
            i = self.buf.find(b"\n", start)
            if i < 0:
                break
            if i - start > self.max:
                raise ProtocolError(f"a line of {i - start} bytes (at most {self.max})")
            line = bytes(self.buf[start:i]).strip()
            if line:
                lines.append(line)
            start = i + 1
        del self.buf[:start]
        if len(self.buf) > self.max:
            raise ProtocolError(f"a line longer than {self.max} bytes")
        return lines
