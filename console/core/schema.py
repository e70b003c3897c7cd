"""Profile schema primitives: a ``Field`` per key, checked with one-line errors.

Plugins declare their sections through the ``haptable_profile_sections`` hook; the
core declares its own in ``console.config.profile``. Key names carry their unit.

A field declares its kind, its range (``min``/``max``: a number, every number of a
list), ``choices``, list lengths, ``max_bytes`` for a string the system limits (a Unix
socket path) and ``check``, a function of one value (each item of a list) returning what
is wrong with it or None (``host_problem``, ``path_problem``). ``explain`` says why a
value is refused, for the one-line error. A command-line option overriding a key takes
the key's range through ``console.core.options.from_field``.
"""

from __future__ import annotations

import ipaddress
import math
import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

REQUIRED = object()

#: Kinds a field may have and how they are described in error messages.
KINDS = {
    "int": "an integer",
    "float": "a number",
    "str": "a string",
    "bool": "true or false",
    "path": "a file path (relative to the profile)",
    "host": "a host name or IP address",
    "floats": "a list of numbers",
    "ints": "a list of integers",
    "strs": "a list of strings",
}


@dataclass(frozen=True)
class Field:
    """One profile key: its kind, default, allowed range or choices, and a help line."""

    kind: str
    default: Any = REQUIRED
    min: float | None = None
    max: float | None = None
    choices: tuple[Any, ...] | None = None
    length: int | None = None  # exact length for list kinds
    min_length: int | None = None
    help: str = ""
    must_exist: bool = True  # for "path": the file must exist
    #: for "str" and "path": the most bytes (UTF-8) the value may take
    max_bytes: int | None = None
    #: a value (each item of a list) -> what is wrong with it, or None
    check: Callable[[Any], str | None] | None = None

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown field kind {self.kind!r}")

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def allowed(self) -> str:
        """What values are allowed, for error messages."""
        what = KINDS[self.kind]
        if self.choices is not None:
            return "one of " + ", ".join(repr(c) for c in self.choices)
        if self.length is not None:
            what += f" of length {self.length}"
        elif self.min_length is not None:
            what += f" of at least {self.min_length} items"
        if self.min is not None and self.max is not None:
            what += f" from {self.min:g} to {self.max:g}"
        elif self.min is not None:
            what += f" >= {self.min:g}"
        elif self.max is not None:
            what += f" <= {self.max:g}"
        if self.max_bytes is not None:
            what += f" of at most {self.max_bytes} bytes"
        return what


#: a host name's part (RFC 1123): letters, digits and '-', not at either end
_LABEL = re.compile(r"(?!-)[A-Za-z0-9-]{1,63}(?<!-)")


def host_problem(text: Any) -> str | None:
    """What keeps ``text`` from being a host name or an IP address, or None. Checked by
    its form only (nothing is looked up): ``256.1.1.1`` and ``10.0.1`` are no IPv4
    address, ``table pc`` no name."""
    if not isinstance(text, str) or not text:
        return "empty: give a host name or an IP address, e.g. 127.0.0.1"
    if not text.isprintable() or any(c.isspace() for c in text):
        return "holds a space or a control character"
    try:
        ipaddress.ip_address(text)
        return None
    except ValueError:
        pass
    labels = text.removesuffix(".").split(".")
    if re.fullmatch(r"[0-9.]+", text) or labels[-1].isdigit():
        return "is no IPv4 address (four numbers from 0 to 255, e.g. 192.168.1.20)"
    if len(text) > 253 or not all(_LABEL.fullmatch(p) for p in labels):
        return (
            "is no host name (letters, digits and '-' in dot-separated parts of 1 to 63 "
            "characters, at most 253 in all)"
        )
    return None


def path_problem(text: Any) -> str | None:
    """What keeps a string from being a file path the system takes (a NUL), or None."""
    if isinstance(text, str) and "\x00" in text:
        return "holds a NUL character (\\x00), which no file path can"
    return None


def _scalar_ok(kind: str, value: Any) -> bool:
    if kind == "int":
        return isinstance(value, int) and not isinstance(value, bool)
    if kind == "float":
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            return False
        try:
            return math.isfinite(float(value))
        except OverflowError:  # an integer beyond any float
            return False
    if kind in ("str", "path"):
        return isinstance(value, str) and (kind == "str" or "\x00" not in value)
    if kind == "host":
        return host_problem(value) is None
    if kind == "bool":
        return isinstance(value, bool)
    return False


def _in_range(f: Field, v: float) -> bool:
    return (f.min is None or v >= f.min) and (f.max is None or v <= f.max)


def _custom_problem(f: Field, value: Any) -> str | None:
    """What ``f.check`` or ``f.max_bytes`` finds wrong with a value of the right kind."""
    items = value if isinstance(value, list) else [value]
    for v in items:
        if f.max_bytes is not None and isinstance(v, str):
            n = len(os.fsencode(os.path.expanduser(v)))
            if n > f.max_bytes:
                return f"{n} bytes, more than the {f.max_bytes} it can take; give a shorter one"
        why = f.check(v) if f.check is not None else None
        if why:
            return f"{_short(v)} {why}" if isinstance(value, list) else why
    return None


def _short(v: Any) -> str:
    text = repr(v)
    return text if len(text) <= 60 else text[:50] + "...'"


def explain(f: Field, value: Any) -> str:
    """Why ``value`` fails ``f`` (after ``check`` said so), for the one-line error."""
    if isinstance(value, str) and f.kind in ("host", "path"):
        why = host_problem(value) if f.kind == "host" else path_problem(value)
        if why:
            return why
    ok, _ = _check_kind(f, value)
    if ok:
        why = _custom_problem(f, value)
        if why:
            return why
    return f"expected {f.allowed()}"


def check(f: Field, value: Any) -> tuple[bool, Any]:
    """Return ``(ok, normalised value)`` for ``value`` against ``f``."""
    ok, norm = _check_kind(f, value)
    if ok and _custom_problem(f, value) is not None:
        return False, None
    return ok, norm


def _check_kind(f: Field, value: Any) -> tuple[bool, Any]:
    if f.kind in ("floats", "ints", "strs"):
        inner = {"floats": "float", "ints": "int", "strs": "str"}[f.kind]
        if not isinstance(value, list) or not all(_scalar_ok(inner, v) for v in value):
            return False, None
        if f.length is not None and len(value) != f.length:
            return False, None
        if f.min_length is not None and len(value) < f.min_length:
            return False, None
        if inner != "str" and not all(_in_range(f, v) for v in value):
            return False, None
        if f.choices is not None and not all(v in f.choices for v in value):
            return False, None
        return True, [float(v) for v in value] if inner == "float" else list(value)
    if not _scalar_ok(f.kind, value):
        return False, None
    if f.choices is not None and value not in f.choices:
        return False, None
    if f.kind in ("int", "float") and not _in_range(f, value):
        return False, None
    return True, float(value) if f.kind == "float" else value
