"""The one-line signal syntax: parsed with ``ast`` against a whitelist, never evaluated.

    seq(sine(250 Hz, 40 V, 0.5 s) * adsr(10 ms, 50 ms, 0.7, 100 ms), silence(0.2 s)) * 3

- Waveforms (peak volts at the actuator): ``sine|square|saw|triangle(FREQ, AMP, DUR)``,
  ``chirp(F0, F1, AMP, DUR)`` (linear), ``logchirp(F0, F1, AMP, DUR)``,
  ``noise(AMP, DUR, seed=0)``, ``silence(DUR)``.
- Envelopes (ratios; without a length they stretch to what they multiply):
  ``adsr(A, D, SUSTAIN, R[, DUR])``, ``ramp(T)`` (linear in and out, what the gate asks),
  ``linramp(FROM, TO[, DUR])``, ``expramp(FROM, TO[, DUR])``.
- Filtering: ``lowpass(a, 4 kHz)`` (zero-phase Butterworth: smooths square/saw edges).
- Breakpoints: ``env(T1, L1, ...)``, ``glide(AMP, T1, F1, ...)``, ``hann()``
  (``console.signals.breakpoints``: what imported haptic files become).
- Combining: ``a + b``, ``a - b`` (sum), ``a * b`` (product: an envelope shapes a signal),
  ``seq(a, b, ...)``, ``repeat(a, N)`` or ``a * N`` (N a whole number: N times over),
  ``a * 50 %`` or ``a * -6 dB`` (a gain), ``-a``.
- Units are written after every value: Hz, kHz; V, mV, Vpp (peak-to-peak); s, ms, us;
  ratios as plain numbers, % or dB.

Every mistake is a ``UserError`` of one line naming the part of the expression and the fix.
The words (units, functions) and the bounds every text is held to before and while it is
parsed (number length and size, printable characters, signs in a row, the dB range) are
in ``console.signals.syntax``; nothing typed can overflow, recurse without end or allocate.
"""

from __future__ import annotations

import ast
from contextvars import ContextVar

from console.core.errors import UserError
from console.core.plain_numbers import plain_s
from console.core.suggest import suggestion
from console.signals import breakpoints
from console.signals.design import (
    ADSR,
    Chirp,
    Gain,
    Level,
    Lowpass,
    Mix,
    Node,
    Noise,
    Ramp,
    Seq,
    Silence,
    Wave,
)
from console.signals.syntax import (
    DATA_FN,
    DIM_NAMES,
    EXAMPLE_UNIT,
    FUNCTIONS,
    MAX_DB,
    MAX_DEPTH,
    MAX_EXPR_CHARS,
    MAX_REPEAT,
    MAX_SIGNS,
    SPEC,
    UNIT_FN,
    UNITS,
    Quantity,
    check_text,
    clip,
    keep_source,
    mark_units,
    number,
    show,
    typed_column,
    unit_column,
    unit_fix,
)

#: the ``data`` of the ``parse`` running (``@NAME`` references), for this call only
_DATA: ContextVar = ContextVar("signal_data", default=None)
#: the text being parsed as typed, its leading blanks and as marked (columns in messages)
_TEXT: ContextVar[tuple[str, int, str]] = ContextVar("signal_text", default=("", 0, ""))


#: Python's words for a syntax error, in the signal language's (the first that matches)
SYNTAX_WORDS = (
    ("forgot a comma", "a comma is missing between two parts (seq(a, b))"),
    ("was never closed", "a bracket opened here is never closed"),
    ("unmatched", "a closing bracket here closes nothing"),
    ("does not match opening", "the brackets do not match"),
    ("invalid decimal literal", "a number runs into a word (write 250 Hz, with a space)"),
    ("unexpected eof", "it ends too early (a value or a bracket is missing)"),
    ("expected an indented block", "it is not one expression"),
    ("invalid syntax", "this is not where a value, a call or an operator can be"),
)


def syntax_words(msg: str) -> str:
    """What a syntax error means in a signal (Python's own words never reach the
    operator: 'invalid syntax. Perhaps you forgot a comma?')."""
    low = (msg or "").lower()
    for key, words in SYNTAX_WORDS:
        if key in low:
            return words
    return "it is not a signal expression"


def parse(text: str, data=None) -> Node:
    """The signal ``text`` describes, or a one-line ``UserError`` naming the bad part.
    ``data`` (``console.signals.breakpoint_data.LibraryData``) resolves ``@NAME``."""
    token, text_token = _DATA.set(data), _TEXT.set(("", 0, ""))
    try:
        return _parse(text)
    finally:
        _DATA.reset(token)
        _TEXT.reset(text_token)


def _parse(text: str) -> Node:
    if not isinstance(text, str) or not text.strip():
        raise UserError("empty signal: write e.g. sine(250 Hz, 20 V, 1 s) * ramp(10 ms)")
    if len(text) > MAX_EXPR_CHARS:
        raise UserError(
            f"signal of {len(text)} characters is too long (at most {MAX_EXPR_CHARS}); "
            "use repeat(...) instead of writing parts out"
        )
    if "\n" in text.strip() or "\r" in text:
        raise UserError("a signal is one line; join its lines")
    for fn in (UNIT_FN, DATA_FN):
        if fn in text:
            raise UserError(f"{fn!r} is not part of the signal syntax; write values as 250 Hz")
    typed = text.strip()
    check_text(typed, len(text) - len(text.lstrip()))
    marked = mark_units(typed)
    try:
        tree = ast.parse(marked, mode="eval")
    except SyntaxError as exc:
        lead = len(text) - len(text.lstrip())  # the column counts in what was typed
        col = f" at column {lead + typed_column(typed, exc.offset)}" if exc.offset else ""
        raise UserError(
            f"signal {clip(text.strip())!r} does not read{col}: {syntax_words(exc.msg)}; "
            "write calls like sine(250 Hz, 20 V, 1 s) with a unit after every value"
        ) from None
    except (RecursionError, MemoryError):
        raise UserError("signal nested too deeply; use seq(...) and repeat(...)") from None
    keep_source(tree, marked)
    _TEXT.set((typed, len(text) - len(text.lstrip()), marked))
    value = _eval(tree.body, 0)
    if not isinstance(value, Node):
        raise UserError(
            f"{text.strip()!r} is a value, not a signal; write e.g. sine({text.strip()}, 20 V, 1 s)"
        )
    return value


def _eval(node: ast.AST, depth: int):
    if depth > MAX_DEPTH:
        raise UserError(f"{show(node)}: nested too deeply (at most {MAX_DEPTH} levels)")
    if isinstance(node, ast.Constant):
        v = node.value
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise UserError(f"{show(node)}: only numbers with units are allowed here")
        return number(v, show(node))
    if isinstance(node, ast.Call):
        return _call(node, depth)
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        return _signed(node, depth)
    if isinstance(node, ast.BinOp):
        return _binop(node, depth)
    if isinstance(node, ast.Name):
        hint = _guess(node.id)
        raise UserError(
            f"{node.id!r} is not part of the signal syntax{hint}; "
            f"use numbers with units and {', '.join(FUNCTIONS)}"
        )
    raise UserError(
        f"{show(node)}: not part of the signal syntax; use numbers with units, "
        f"{', '.join(FUNCTIONS)}, + - and *"
    )


def _signed(node: ast.UnaryOp, depth: int):
    """``-x``, ``+x``: a run of signs folded without recursion (and kept short)."""
    negative, signs, inner = False, 0, node
    while isinstance(inner, ast.UnaryOp) and isinstance(inner.op, (ast.USub, ast.UAdd)):
        negative ^= isinstance(inner.op, ast.USub)
        signs += 1
        inner = inner.operand
    if signs > MAX_SIGNS:
        raise UserError(
            f"{signs} signs in a row before {show(inner)}: nested too deeply (at most "
            f"{MAX_SIGNS}); write one '-' (or none)"
        )
    v = _eval(inner, depth + signs)
    if not negative:
        return v
    if isinstance(v, Node):
        return Gain(-1.0, v, show(node))
    if isinstance(v, Quantity):
        return Quantity(-v.value, v.dim, show(node))
    return -v


def _guess(name: str) -> str:
    return suggestion(name, [*FUNCTIONS, *UNITS])


def _binop(node: ast.BinOp, depth: int) -> Node:
    part = show(node)
    if not isinstance(node.op, (ast.Add, ast.Sub, ast.Mult)):
        raise UserError(
            f"{part}: only +, - and * combine signals; for a gain write x * 50 % or x * -6 dB"
        )
    a, b = _eval(node.left, depth + 1), _eval(node.right, depth + 1)
    if isinstance(node.op, ast.Mult):
        if not isinstance(a, Node):
            a, b = b, a
        if isinstance(a, Node) and isinstance(b, Node):
            if a.volts and b.volts:
                raise UserError(
                    f"{part}: a product of two signals in volts would be in volts squared; "
                    "give the modulator a ratio amplitude (e.g. sine(5 Hz, 100 %, 1 s))"
                )
            return Mix("*", (a, b), part)
        if isinstance(a, Node):
            return _scaled(a, b, part)
    elif isinstance(a, Node) and isinstance(b, Node):
        if a.volts != b.volts:
            raise UserError(f"{part}: adds volts to a ratio; {_both_units}")
        if isinstance(node.op, ast.Sub):
            b = Gain(-1.0, b, f"-{b.text}")
        return Mix("+", (a, b), part)
    raise UserError(
        f"{part}: {'+' if isinstance(node.op, ast.Add) else '-' if isinstance(node.op, ast.Sub) else '*'} "
        "needs signals on both sides (a value goes inside a call: sine(250 Hz, 20 V, 1 s))"
    )


_both_units = "give both parts amplitudes in V (or both in %)"


def _scaled(sig: Node, k, part: str) -> Node:
    """``sig * N`` repeats N times; ``sig * 50 %`` and ``sig * -6 dB`` are gains."""
    if isinstance(k, Quantity) and k.dim in ("ratio", "dB"):
        return Gain(_ratio(k, part), sig, part)
    if isinstance(k, int) and not isinstance(k, bool):
        return _repeat(sig, k, part)
    raise UserError(
        f"{part}: a plain number after * is a repeat count (a whole number); for a gain "
        f"write {_show_k(k)} as a percentage or in dB (x * 50 %, x * -6 dB)"
    )


def _show_k(k) -> str:
    return k.text if isinstance(k, Quantity) else f"{k!r}"


def _repeat(sig: Node, count, part: str) -> Node:
    if not isinstance(count, int) or isinstance(count, bool) or not 1 <= count <= MAX_REPEAT:
        raise UserError(
            f"{part}: repeat count {_show_k(count)}; give a whole number from 1 to {MAX_REPEAT}"
        )
    if sig.duration_s() is None:
        raise UserError(f"{part}: an envelope alone cannot repeat; multiply it by a signal first")
    return Seq((sig,), count, part)


def _ratio(q, part: str) -> float:
    if isinstance(q, Quantity) and q.dim == "dB":
        if not -MAX_DB <= q.value <= MAX_DB:
            raise UserError(
                f"{part}: gain {q.text} is outside -{MAX_DB:g}..{MAX_DB:g} dB; give a gain "
                "within it (or an amplitude in V)"
            )
        return 10.0 ** (q.value / 20.0)
    if isinstance(q, Quantity) and q.dim == "ratio":
        return q.value
    if isinstance(q, (int, float)) and not isinstance(q, bool):
        return float(q)
    raise UserError(f"{part}: {_show_k(q)} is not a ratio; give a plain number, % or dB")


def _call(node: ast.Call, depth: int):
    part = show(node)
    if not isinstance(node.func, ast.Name):
        raise UserError(f"{part}: call one of {', '.join(FUNCTIONS)} by name")
    name = node.func.id
    if name == UNIT_FN:
        value = number(node.args[0].value, part)  # the regex only marks plain numbers
        if node.args[1].value not in UNITS:
            raise UserError(_unit_said(node, unit_fix(node.args[1].value)))
        dim, factor = UNITS[node.args[1].value]
        return Quantity(float(value) * factor, dim, part)
    if name == DATA_FN:  # the mark of @NAME (the regex only marks names)
        return breakpoints.data_ref(node.args[0].value, part, _DATA.get())
    if name == "seq":
        if node.keywords or not node.args:
            raise UserError(f"{part}: seq takes the signals to play one after the other")
        parts = tuple(_eval(a, depth + 1) for a in node.args)
        for a, p in zip(node.args, parts, strict=True):
            if not isinstance(p, Node) or p.duration_s() is None:
                raise UserError(
                    f"{part}: {show(a)} has no length of its own; seq takes signals "
                    "(multiply an envelope by a signal first)"
                )
        if len({p.volts for p in parts}) > 1:
            raise UserError(f"{part}: mixes volts and ratios; {_both_units}")
        return Seq(parts, 1, part)
    if name in breakpoints.NAMES:
        args = [_eval(a, depth + 1) for a in node.args]
        return breakpoints.build(name, args, bool(node.keywords), part)
    if name not in SPEC:
        raise UserError(
            f"{part}: unknown function {name!r}{_guess(name)}; use {', '.join(FUNCTIONS)}"
        )
    spec = SPEC[name]
    args = _bind(name, spec, node, depth, part)
    return _build(name, args, part)


def _bind(name: str, spec, node: ast.Call, depth: int, part: str) -> dict:
    usage = f"{name}({', '.join(p for p, _d, _x in spec)})"
    if len(node.args) > len(spec):
        raise UserError(f"{part}: too many values; {usage}")
    given: dict[str, ast.AST] = {}
    for (pname, _d, _x), a in zip(spec, node.args, strict=False):
        given[pname] = a
    names = [p for p, _d, _x in spec]
    for kw in node.keywords:
        if kw.arg is None or kw.arg not in names:
            raise UserError(f"{part}: unknown parameter {kw.arg!r}; {usage}")
        if kw.arg in given:
            raise UserError(f"{part}: {kw.arg} given twice; {usage}")
        given[kw.arg] = kw.value
    out = {}
    for pname, dim, default in spec:
        if pname not in given:
            if default is None:
                raise UserError(f"{part}: missing {pname}; {usage}")
            out[pname] = None if default == "" else default
            continue
        _known_unit(given[pname], f"{name}'s {pname}", dim)
        v = _eval(given[pname], depth + 1)
        if pname == "amplitude":
            out["_volts"] = not (isinstance(v, Quantity) and v.dim in ("ratio", "dB"))
        out[pname] = _value(v, dim, pname, part, given[pname])
    return out


def _value(v, dim: str, pname: str, part: str, node: ast.AST):
    shown = show(node)
    if dim == "node":
        if not isinstance(v, Node):
            raise UserError(f"{part}: {pname} {shown} is not a signal")
        return v
    if dim == "int":
        if not isinstance(v, int) or isinstance(v, bool):
            raise UserError(f"{part}: {pname} {shown} must be a whole number")
        return v
    if isinstance(v, Node):
        raise UserError(f"{part}: {pname} {shown} is a signal; give {DIM_NAMES.get(dim, dim)}")
    if dim == "ratio" or (dim == "V" and isinstance(v, Quantity) and v.dim in ("ratio", "dB")):
        return _ratio(v, part)
    if not isinstance(v, Quantity):
        raise UserError(f"{part}: {pname} {shown} needs a unit; write {shown} {EXAMPLE_UNIT[dim]}")
    if v.dim != dim:
        raise UserError(
            f"{part}: {pname} {v.text} is {DIM_NAMES.get(v.dim, v.dim)}, expected "
            f"{DIM_NAMES[dim]} (in {', '.join(u for u, (d, _f) in UNITS.items() if d == dim)})"
            f"{_at(node).replace(' at', ',', 1)}"
        )
    return v.value


def _is_unit(node: ast.AST) -> bool:
    return (
        isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == UNIT_FN
    )


def _known_unit(node: ast.AST, wants: str, dim: str) -> None:
    """A value's unit the language does not know, named with what the value takes
    (``sine's frequency takes Hz or kHz``); the rest is checked once it is a value."""
    if _is_unit(node) and dim in ("Hz", "V", "s") and node.args[1].value not in UNITS:
        dims = ("V", "ratio", "dB") if dim == "V" else (dim,)
        raise UserError(_unit_said(node, unit_fix(node.args[1].value, wants, dims)))


def _unit_said(node: ast.Call, fix: str) -> str:
    """``unit 'hz' at column 10 (250 hz): write Hz; ...``: the unit's column as typed."""
    typed, lead, _marked = _TEXT.get()
    col = _column(node)
    at = f" at column {lead + unit_column(typed, col)}" if col else ""
    return f"unit {node.args[1].value!r}{at} ({show(node)}): {fix}"


def _column(node: ast.AST) -> int | None:
    """Where ``node`` starts in the text as typed (1-based, without its leading blanks)."""
    typed, _lead, marked = _TEXT.get()
    if not typed or not isinstance(node, ast.expr):
        return None
    start = len(marked.encode("utf-8")[: node.col_offset].decode("utf-8", "replace"))
    return typed_column(typed, start + 1)


def _at(node: ast.AST) -> str:
    """`` at column N``: where ``node`` starts in the text as typed."""
    col = _column(node)
    return f" at column {_TEXT.get()[1] + col}" if col else ""


def _need(ok: bool, part: str, message: str) -> None:
    if not ok:
        raise UserError(f"{part}: {message}")


def _build(name: str, a: dict, part: str) -> Node:
    for key in ("duration", "attack", "decay", "release", "ramp"):
        d = a.get(key)
        if d is not None:
            _need(d >= 0, part, f"{key} {plain_s(d)} is negative; give a length of 0 s or more")
    if a.get("duration") is not None and name not in ("silence",):
        _need(a["duration"] > 0, part, "duration 0 s; give a positive length")
    if name in ("sine", "square", "saw", "triangle"):
        _need(a["frequency"] > 0, part, "frequency must be above 0 Hz")
        return Wave(name, a["frequency"], a["amplitude"], a["duration"], part, a["_volts"])
    if name in ("chirp", "logchirp"):
        log = name == "logchirp"
        for k in ("f0", "f1"):
            _need(a[k] > 0 if log else a[k] >= 0, part, f"{k} must be above 0 Hz")
        return Chirp(a["f0"], a["f1"], a["amplitude"], a["duration"], log, part, a["_volts"])
    if name == "noise":
        _need(0 <= a["seed"] < 2**63, part, "seed must be a whole number from 0")
        return Noise(a["amplitude"], a["duration"], a["seed"], part, a["_volts"])
    if name == "silence":
        return Silence(a["duration"], part)
    if name == "adsr":
        _need(0 <= a["sustain"] <= 1, part, f"sustain {a['sustain']:g} must be from 0 to 1")
        return ADSR(a["attack"], a["decay"], a["sustain"], a["release"], a["duration"], part)
    if name == "ramp":
        _need(a["ramp"] > 0, part, "ramp 0 s; give its length, e.g. ramp(10 ms)")
        return Ramp(a["ramp"], part)
    if name in ("linramp", "expramp"):
        exp = name == "expramp"
        if exp:
            _need(
                a["start"] > 0 and a["end"] > 0,
                part,
                "an exponential ramp runs between levels above 0 (e.g. 1 %)",
            )
        return Level(a["start"], a["end"], exp, a["duration"], part)
    if name == "repeat":
        return _repeat(a["signal"], a["count"], part)
    if name == "lowpass":
        _need(a["cutoff"] > 0, part, "cutoff must be above 0 Hz")
        _need(a["signal"].duration_s() is not None, part, "filter a signal, not an envelope")
        return Lowpass(a["signal"], a["cutoff"], part)
    raise AssertionError(name)  # pragma: no cover
