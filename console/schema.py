"""Profile schema primitives: a ``Field`` per key, checked with one-line errors.

Plugins declare their sections through the ``haptable_profile_sections`` hook; the
core declares its own in ``console.profile``. Key names carry their unit.
"""

from __future__ import annotations

import math
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
        return what


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
        return isinstance(value, str)
    if kind == "bool":
        return isinstance(value, bool)
    return False


def _in_range(f: Field, v: float) -> bool:
    return (f.min is None or v >= f.min) and (f.max is None or v <= f.max)


def check(f: Field, value: Any) -> tuple[bool, Any]:
    """Return ``(ok, normalised value)`` for ``value`` against ``f``."""
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
