"""The signal syntax's words: units, functions and their parameters, and the bounds a
signal's text is held to before and while it is parsed (``console.signals.expr``).

Bounds are checked on the text and on each literal before any conversion, so nothing an
operator types can overflow, recurse without end or allocate: a number of at most
``MAX_NUMBER_CHARS`` characters and ``MAX_MAGNITUDE`` in size, only printable
characters, no comments, a gain within +-``MAX_DB`` dB, ``MAX_SIGNS`` signs in a row.
"""

from __future__ import annotations

import ast
import keyword
import math
import re
from dataclasses import dataclass

from console.core.errors import UserError

MAX_EXPR_CHARS = 2000
MAX_DEPTH = 40
MAX_REPEAT = 100_000
#: a number is at most this many characters as written (``1.2345e-3``: 9) ...
MAX_NUMBER_CHARS = 30
#: ... and at most this large: far above any frequency, voltage, count or seed a signal
#: uses, far below where ``float`` overflows
MAX_MAGNITUDE = 1e18
#: a gain in dB within +-this (1e10 as a ratio)
MAX_DB = 200.0
#: ``-`` and ``+`` in a row before a value or signal
MAX_SIGNS = 2
#: a token that starts like a number: digits, a point, letters (exponent, hex), ``_``
_NUMBER_TOKEN = re.compile(r"(?<![\w.])\.?\d[\w.]*")

#: unit -> (dimension, factor to SI); dB is converted where it is used
UNITS: dict[str, tuple[str, float]] = {
    "Hz": ("Hz", 1.0),
    "kHz": ("Hz", 1e3),
    "V": ("V", 1.0),
    "mV": ("V", 1e-3),
    "Vpp": ("V", 0.5),
    "s": ("s", 1.0),
    "ms": ("s", 1e-3),
    "us": ("s", 1e-6),
    "%": ("ratio", 1e-2),
    "dB": ("dB", 1.0),
}
UNIT_FN = "_unit_"
_NUMBER = r"(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
#: a number and the word after it: a unit, known or not (``250 hz``, ``0.5 sec``, ``250 kV``
#: are marked too, so a wrong unit is named as one, never read as a missing comma); a word
#: followed by ``(`` is a call, not a unit
_QUANTITY = re.compile(
    rf"(?<![\w.])((?>{_NUMBER}))\s*(%|[A-Za-z\u00b5\u03bc][A-Za-z0-9]*)(?![\w\u00b5\u03bc])(?!\s*\()",
    re.ASCII,
)
DIM_NAMES = {"Hz": "a frequency", "V": "a voltage", "s": "a duration", "ratio": "a ratio"}
EXAMPLE_UNIT = {"Hz": "Hz", "V": "V", "s": "s"}


@dataclass(frozen=True)
class Quantity:
    value: float  # SI (Hz, V peak, s), a ratio, or dB
    dim: str
    text: str


# name -> ((parameter, dimension, default or None) ...); "int" and "ratio" are plain
SPEC: dict[str, tuple[tuple[str, str, object], ...]] = {
    "sine": (("frequency", "Hz", None), ("amplitude", "V", None), ("duration", "s", None)),
    "square": (("frequency", "Hz", None), ("amplitude", "V", None), ("duration", "s", None)),
    "saw": (("frequency", "Hz", None), ("amplitude", "V", None), ("duration", "s", None)),
    "triangle": (("frequency", "Hz", None), ("amplitude", "V", None), ("duration", "s", None)),
    "chirp": (("f0", "Hz", None), ("f1", "Hz", None), ("amplitude", "V", None), ("duration", "s", None)),
    "logchirp": (("f0", "Hz", None), ("f1", "Hz", None), ("amplitude", "V", None), ("duration", "s", None)),
    "noise": (("amplitude", "V", None), ("duration", "s", None), ("seed", "int", 0)),
    "silence": (("duration", "s", None),),
    "adsr": (("attack", "s", None), ("decay", "s", None), ("sustain", "ratio", None), ("release", "s", None), ("duration", "s", "")),
    "ramp": (("ramp", "s", None),),
    "linramp": (("start", "ratio", None), ("end", "ratio", None), ("duration", "s", "")),
    "expramp": (("start", "ratio", None), ("end", "ratio", None), ("duration", "s", "")),
    "repeat": (("signal", "node", None), ("count", "int", None)),
    "lowpass": (("signal", "node", None), ("cutoff", "Hz", None)),
}  # fmt: skip
FUNCTIONS = (*SPEC, "seq", "env", "glide", "hann", "bursts")  # the last four: breakpoints
#: ``@name``: breakpoint data kept beside the library (``console.signals.breakpoint_data``)
DATA_FN = "_data_"
_DATA_REF = re.compile(r"(?<![\w@])@([A-Za-z0-9][A-Za-z0-9_-]{0,39})(?![\w-])", re.ASCII)
_MARKABLE = re.compile(f"{_QUANTITY.pattern}|{_DATA_REF.pattern}", re.ASCII)


def mark_units(text: str) -> str:
    """``250 Hz`` -> ``_unit_(250, "Hz")`` and ``@name`` -> ``_data_("name")``: Python's
    grammar has neither units nor data references."""
    return _MARKABLE.sub(_mark, text)


def _mark(m: re.Match[str]) -> str:
    if m.group(3) is not None:
        return f'{DATA_FN}("{m.group(3)}")'
    if keyword.iskeyword(m.group(2)):  # ``1 if ...``: Python's, refused as not a signal
        return m.group(0)
    return f'{UNIT_FN}({m.group(1)}, "{m.group(2)}")'


#: how else a unit is written -> the signal language's spelling
_ALIASES = {
    "sec": "s", "secs": "s", "second": "s", "seconds": "s",
    "msec": "ms", "msecs": "ms", "millisecond": "ms", "milliseconds": "ms",
    "usec": "us", "usecs": "us", "\u00b5s": "us", "\u03bcs": "us", "microsecond": "us",
    "microseconds": "us", "hertz": "Hz", "volt": "V", "volts": "V", "millivolt": "mV",
    "millivolts": "mV", "pct": "%", "percent": "%", "db": "dB",
}  # fmt: skip
_BY_CASE = {u.casefold(): u for u in UNITS}


def units_of(*dims: str) -> str:
    """The units values of ``dims`` are written in: ``Hz or kHz``, ``s, ms or us``."""
    names = [u for u, (d, _f) in UNITS.items() if d in dims]
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"


def unit_fix(word: str, wants: str = "", dims: tuple[str, ...] = ()) -> str:
    """What to write instead of ``word``, a unit the signal language does not know:
    its spelling here (``hz``: ``write Hz``), else that it is none, and what the value
    takes (``wants``, e.g. ``sine's frequency``, in ``dims``: ``takes Hz or kHz``)."""
    known = _ALIASES.get(word) or _ALIASES.get(word.casefold()) or _BY_CASE.get(word.casefold())
    takes = f"; {wants} takes {units_of(*dims)}" if wants else ""
    if known and (not dims or UNITS[known][0] in dims):
        return f"write {known}{takes}"
    if known:
        return f"{known} is {DIM_NAMES.get(UNITS[known][0], 'a gain')}{takes}"
    every = "; ".join(units_of(d) for d in ("Hz", "V", "s")) + "; % or dB"
    return f"not a unit of the signal language{takes or f' (units: {every})'}"


def unit_column(text: str, col: int) -> int:
    """The 1-based column of the unit of the quantity that starts at ``col`` of ``text``."""
    m = _QUANTITY.match(text, col - 1)
    return m.start(2) + 1 if m else col


def typed_column(text: str, marked_col: int) -> int:
    """The 1-based column in ``text`` of column ``marked_col`` of ``mark_units(text)``
    (a unit's mark stands for its whole quantity)."""
    at, shift = marked_col - 1, 0  # shift: how much longer the marks made the text
    for m in _MARKABLE.finditer(text):
        start = m.start() + shift
        if at < start:
            break
        mark = len(_mark(m))
        if at < start + mark:
            return m.start() + 1
        shift += mark - (m.end() - m.start())
    return at - shift + 1


_MARKED = re.compile(rf"""{UNIT_FN}\(([^,]+), ["']([^"']+)["']\)|{DATA_FN}\("([^"]+)"\)""")


def _unmark(m: re.Match[str]) -> str:
    return f"@{m.group(3)}" if m.group(3) is not None else f"{m.group(1)} {m.group(2)}"


def keep_source(tree: ast.AST, marked: str) -> None:
    """Give every part of ``tree`` the text it was parsed from (``show`` returns it): one
    slice per part, where ``ast.unparse`` at every level would cost the square."""
    raw = marked.encode("utf-8")  # ast's columns count UTF-8 bytes
    for n in ast.walk(tree):
        if isinstance(n, ast.expr):
            part = raw[n.col_offset : n.end_col_offset].decode("utf-8", "replace")
            if UNIT_FN in part or DATA_FN in part:
                part = _MARKED.sub(_unmark, part)
            n._source = part  # type: ignore[attr-defined]


def show(node: ast.AST) -> str:
    """The part as the operator wrote it (units back in place), at most 120 characters."""
    text = getattr(node, "_source", None)
    if text is None:
        try:
            text = _MARKED.sub(_unmark, ast.unparse(node))
        except RecursionError:  # a deep part: its head says which one
            text = type(node).__name__
    return clip(text)


def clip(text: str, limit: int = 120) -> str:
    """``text`` short enough for a message line."""
    return text if len(text) <= limit else text[: limit - 20] + f"... ({len(text)} characters)"


#: the signs the signal language writes with, beside letters, digits and blanks
SIGNS = "(),.+-*%=@"
#: what to write instead of a character the language does not use (the first group
#: holding it); any other: ``_ANY_FIX``
_CHAR_FIXES = (
    ("[]{}", "group with ( ) and write a value as it is: 250 Hz, not [250] Hz"),
    (";:", "separate values and parts with a comma: sine(250 Hz, 20 V, 1 s), seq(a, b)"),
    ("'\"`\u2018\u2019\u201c\u201d", "write values and names without quotes"),
    ("\u00d7\u00b7\u2217\u22c5", "multiply with *"),
    ("\u2212\u2013\u2014\u2010\u2011", "write the minus as -"),
    ("/|&^<>\u00f7", "only +, - and * combine signals; for a gain write x * 50 % or x * -6 dB"),
    ("#", "put a note in the description instead"),
)
_ANY_FIX = "write calls like sine(250 Hz, 20 V, 1 s) * ramp(10 ms)"


def _used(c: str) -> bool:
    """Whether the signal language writes with ``c``: a letter (a word's: a name or a
    unit, ``\u00b5s`` too), a digit, a blank or one of ``SIGNS``."""
    return c in SIGNS or c in " \t" or (c.isascii() and c.isdigit()) or c.isidentifier()


def check_text(text: str, lead: int = 0) -> None:
    """Refuse what Python's grammar would take, or misread, but a signal must not hold:
    characters that are not printable (control codes, a byte that was not UTF-8), any
    the language does not write with (one rule: ``[`` was read as a missing comma, ``#``
    as a comment), numbers too long to be meant. Runs before ``ast.parse`` so nothing
    big is ever built. ``lead``: blanks typed before ``text`` (columns count them)."""
    for col, c in enumerate(text, lead + 1):
        if not c.isprintable() and c != "\t":
            raise UserError(
                f"signal has {c!r} at column {col}, not a printable character (a control "
                "code, or a byte that is not UTF-8); retype the signal without it"
            )
    for col, c in enumerate(text, lead + 1):
        if not _used(c):
            fix = next((f for chars, f in _CHAR_FIXES if c in chars), _ANY_FIX)
            raise UserError(
                f"{c!r} at column {col} is not part of the signal syntax (it writes with "
                f"letters, digits and {' '.join(SIGNS)}); {fix}"
            )
    for m in _NUMBER_TOKEN.finditer(text):
        if len(m.group()) > MAX_NUMBER_CHARS:
            raise UserError(
                f"number {m.group()[:12]}... at column {lead + m.start() + 1} is {len(m.group())} "
                f"characters long (at most {MAX_NUMBER_CHARS}); write it shorter, e.g. 2.5e3"
            )


def number(v: int | float, shown: str) -> int | float:
    """A literal within bounds (compared before any conversion: a long ``int`` never
    reaches ``float``)."""
    if isinstance(v, float) and not math.isfinite(v):
        raise UserError(f"{shown}: not a finite number; give a smaller value")
    if abs(v) > MAX_MAGNITUDE:
        raise UserError(
            f"{shown}: {float(v):.3g} is larger than any value a signal uses (at most "
            f"{MAX_MAGNITUDE:.0e}); check the number"
        )
    return v
