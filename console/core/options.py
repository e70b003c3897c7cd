"""Command-line numbers, each declared once with its range, and a parser that says
what is wrong in one line.

A command declares every number it takes where it adds the option, with a converter
from here as argparse's ``type=``::

    p.add_argument("--port", type=port())
    p.add_argument("--min-contrast-db", type=finite_float(0, 200, unit="dB"))
    p.add_argument("--sectors", type=from_field(KNOB_FIELDS["sectors"]))
    p.add_argument("--seconds", type=seconds(zero="until Ctrl-C"))

argparse calls the converter with the text typed; NaN, infinity, a value out of range, a
fraction where a count is asked or text that is no number is refused before the command
runs, as one line naming the command, the option, the value and what to give
(``haptable: error: tuio --port: -1 is out of range; give a whole number from 1 to
65535``, exit 2). An option that overrides a profile key takes the key's range
(``from_field``), so the two never disagree. ``Parser`` is the ``argparse.ArgumentParser``
of the ``haptable`` command and its sub-commands: any usage error (unknown option,
missing argument, bad choice) is that one line too (``UsageError``), never the usage text.

tests/console/test_cli_numbers.py walks every command's parser and fails on a number
option declared with a plain ``type=int`` or ``type=float``.
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING, NoReturn

from console.core.errors import UsageError, UserError
from console.core.schema import host_problem
from console.core.suggest import suggestion

if TYPE_CHECKING:
    from console.core.schema import Field

#: The longest a command may be asked to run (``--seconds``, ``--minutes``): a week.
#: Longer is a typo (``1e308``); 0 where allowed means "until Ctrl-C".
MAX_RUN_S = 7 * 24 * 3600.0
#: The largest seed: numpy's and the standard library's generators take any integer
#: from 0; 2**63 - 1 is what a signed 64-bit JSON reader keeps (the studies' bound too).
MAX_SEED = 2**63 - 1
#: How much of a bad value a message repeats.
SHOWN_CHARS = 40


def _num(v: float) -> str:
    """A number as a person writes it: ``65535``, ``0.5``, ``1e+300``."""
    if isinstance(v, int):
        return str(v) if len(str(abs(v))) <= 20 else f"a {len(str(abs(v)))}-digit number"
    if v.is_integer() and abs(v) < 1e7:
        return str(int(v))
    return f"{v:g}"


def shown(text: str) -> str:
    """The value a user typed, as a message repeats it: one line, cut when long."""
    t = "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
    if len(t) > SHOWN_CHARS:
        t = t[: SHOWN_CHARS - 3] + f"... ({len(text)} characters)"
    return t if t.strip() == t and t else repr(text)[: SHOWN_CHARS + 2]


class BadValue(argparse.ArgumentTypeError):
    """A typed value a converter refused: the value (as typed) and what to give. Alone
    it reads ``0: out of range; give ...``; ``Parser`` puts the command and the option
    before it: ``tuio --port 0: out of range; give ...``."""

    def __init__(self, text: str, why: str) -> None:
        self.shown, self.why = shown(text), why
        super().__init__(f"{self.shown}: {why}")


@dataclass(frozen=True)
class Number:
    """An argparse ``type=``: the text typed -> an ``int`` or a finite ``float`` within
    ``[lo, hi]`` (``above``: ``lo`` itself excluded), else ``argparse.ArgumentTypeError``
    with what to give. ``note`` follows the range in the message and the help (what 0
    means, the default)."""

    lo: float | None = None
    hi: float | None = None
    integer: bool = False
    above: bool = False
    unit: str = ""
    note: str = ""

    @property
    def __name__(self) -> str:  # argparse names a type by it
        return "integer" if self.integer else "number"

    def describe(self) -> str:
        """``a whole number from 1 to 65535``, ``a number above 0 up to 1000 Hz``."""
        what = "a whole number" if self.integer else "a number"
        lo = None if self.lo is None else _num(self.lo)
        hi = None if self.hi is None else _num(self.hi)
        if lo is not None and hi is not None:
            rng = f"above {lo} up to {hi}" if self.above else f"from {lo} to {hi}"
        elif lo is not None:
            rng = f"above {lo}" if self.above else f"{lo} or more"
        elif hi is not None:
            rng = f"up to {hi}"
        else:
            rng = "" if self.integer else "(finite)"
        text = " ".join(p for p in (what, rng, self.unit) if p)
        return f"{text} ({self.note})" if self.note else text

    def problem(self, value: float) -> str | None:
        """Why ``value`` (already a number) is refused, or None."""
        if isinstance(value, float) and not math.isfinite(value):
            return "not a finite number"
        if self.integer and isinstance(value, float) and not value.is_integer():
            return "not a whole number"
        low = self.lo is not None and (value <= self.lo if self.above else value < self.lo)
        if low or (self.hi is not None and value > self.hi):
            return "out of range"
        return None

    def __call__(self, text: str) -> int | float:
        value = _parse(text, self.integer)
        why = "not a number" if value is None else self.problem(value)
        if why is not None:
            raise BadValue(text, f"{why}; give {self.describe()}")
        assert value is not None
        return int(value) if self.integer else float(value)

    def check(self, value: float | None, flag: str) -> float | None:
        """``value`` (from code, not typed: ``None`` passes) checked the same way, else a
        one-line ``UserError`` naming ``flag``."""
        if value is None:
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise UserError(f"{flag} {value!r}: give {self.describe()}")
        why = self.problem(value)
        if why is not None:
            raise UserError(f"{flag} {_num(value)}: {why}; give {self.describe()}")
        return value


def _parse(text: str, integer: bool) -> int | float | None:
    """A number from typed text (None: none). An integer is parsed as one (no rounding
    through float); ``1e3`` or ``3.5`` where a count is asked is read as a float, which
    ``Number.problem`` then judges."""
    t = text.strip()
    if not t or len(t) > 400:  # no setting needs more digits; int() of 5000 refuses anyway
        return None
    if integer and re.fullmatch(r"[+-]?\d[\d_]*", t):
        try:
            return int(t)
        except ValueError:
            return None
    try:
        return float(t)
    except ValueError:
        return None


def finite_float(
    lo: float | None = None,
    hi: float | None = None,
    *,
    above: bool = False,
    unit: str = "",
    note: str = "",
) -> Number:
    """A finite number within ``[lo, hi]`` (``above``: greater than ``lo``)."""
    return Number(lo, hi, False, above, unit, note)


def integer(
    lo: int | None = None, hi: int | None = None, *, unit: str = "", note: str = ""
) -> Number:
    """A whole number within ``[lo, hi]``."""
    return Number(lo, hi, True, False, unit, note)


def positive_int(hi: int, *, unit: str = "", note: str = "") -> Number:
    """A count: a whole number from 1 to ``hi``."""
    return Number(1, hi, True, False, unit, note)


def port(note: str = "") -> Number:
    """A UDP or TCP port to send to: 1 to 65535 (0 would mean "any port", which a
    sender cannot send to)."""
    return Number(1, 65535, True, False, "", note)


def seed() -> Number:
    """A random seed: 0 to ``MAX_SEED``."""
    return Number(0, MAX_SEED, True)


def seconds(
    hi: float = MAX_RUN_S, *, lo: float = 0.0, above: bool = False, zero: str = ""
) -> Number:
    """A duration in seconds, ``lo`` to ``hi`` (``zero``: what 0 means, e.g. "until
    Ctrl-C")."""
    return Number(lo, hi, False, above, "s", f"0: {zero}" if zero else "")


def minutes(hi: float = MAX_RUN_S / 60) -> Number:
    """A duration in minutes, above 0."""
    return Number(0.0, hi, False, True, "min")


def from_field(field: Field, *, unit: str = "", note: str = "") -> Number:
    """The converter of an option that overrides a profile key: the key's kind and
    range (``console.core.schema.Field``)."""
    if field.kind not in ("int", "float"):
        raise ValueError(f"a {field.kind} field is no number")
    return Number(field.min, field.max, field.kind == "int", False, unit, note)


def host_name(text: str) -> str:
    """An argparse ``type=`` for a host to send to: a host name or an IP address by its
    form (``console.core.schema.host_problem``; nothing is looked up here)."""
    why = host_problem(text)
    if why:
        raise BadValue(text, why.removeprefix("empty: ").removeprefix("is "))
    return text


def seconds_option(value: float | None, flag: str) -> float | None:
    """A duration given in code (not typed) checked: finite, 0 to a week (``None``: not
    given); else a one-line ``UserError``. Typed options use ``type=seconds()``."""
    return seconds().check(value, flag)


# --------------------------------------------------------------------------- the parser
def usage_line(prog: str, message: str) -> str:
    """argparse's complaint as one line naming the command and the option:
    ``knob --sectors: 0 is out of range; give ...``."""
    cmd = prog.removeprefix("haptable").strip()
    m = re.fullmatch(r"argument (\S+?): (.*)", message, re.S)
    if m:
        opt, rest = m.group(1).split("/")[0], m.group(2)
        where = f"{cmd} {opt}".strip()
    else:
        where, rest = cmd, message
    see = f"{prog} --help"
    if "invalid" not in rest and "give " not in rest and "choose from" not in rest:
        rest += f" (see `{see}`)"
    text = f"{where}: {rest}" if where else rest
    return " ".join(text.split())


def _option_strings(parser: argparse.ArgumentParser) -> set[str]:
    """Every long option of ``parser`` and of its sub-commands' parsers."""
    out: set[str] = set()
    for action in parser._actions:
        out |= {o for o in action.option_strings if o.startswith("--")}
        if isinstance(action, argparse._SubParsersAction):
            for sub in set(action.choices.values()):
                out |= _option_strings(sub)
    return out


class Parser(argparse.ArgumentParser):
    """``argparse.ArgumentParser`` whose usage errors raise ``UsageError`` (one line,
    exit 2 from ``console.cli.main``) instead of printing the usage and exiting. Sub-parsers
    are of this class too."""

    def error(self, message: str) -> NoReturn:
        if message.startswith("unrecognized arguments:"):  # a mistyped option: the one meant
            bad = next((w for w in message.split()[2:] if w.startswith("--")), "")
            own = {o for a in self._actions for o in a.option_strings}
            if bad.split("=")[0] in own:  # its own option, given before the command's name
                raise UsageError(
                    f"{bad} goes after the command's name: `{self.prog} {bad}` "
                    f"(see `{self.prog} --help`)"
                )
            hint = suggestion(
                bad.split("=")[0], sorted(_option_strings(self)), "did you mean {!r}?"
            )
            if hint:
                message = f"{message}; {hint}"
        raise UsageError(usage_line(self.prog, message))

    def parse_args(self, args=None, namespace=None):  # type: ignore[override]
        """Unrecognized arguments are told by the sub-command they were given to: its
        options are suggested, its ``--help`` named (``haptable doctor --help``)."""
        words = list(sys.argv[1:] if args is None else args)
        unknown = self._unknown_before_command(words)
        if unknown:  # else its value is read as the command (``invalid choice: 'sim'``)
            self.error(f"unrecognized arguments: {unknown}")
        ns, extras = self.parse_known_args(args, namespace)
        if extras:
            words = list(sys.argv[1:] if args is None else args)
            self._named_sub(words).error(f"unrecognized arguments: {' '.join(extras)}")
        return ns

    def _unknown_before_command(self, words: list[str]) -> str:
        """The first ``--option`` before the command's name that is none of this
        parser's (nor a prefix of one), "" when none or the parser has no commands."""
        subs = [a for a in self._actions if isinstance(a, argparse._SubParsersAction)]
        if not subs:
            return ""
        own = {o for a in self._actions for o in a.option_strings}
        # a command's own option given before it is told where it goes (``parse_known``)
        own |= {o for p in subs[0].choices.values() for a in p._actions for o in a.option_strings}
        for w in words:
            if w == "--" or w in subs[0].choices:
                return ""
            name = w.split("=")[0]
            if w.startswith("--") and not any(o.startswith(name) for o in own):
                return w
        return ""

    def _named_sub(self, words: list[str]) -> argparse.ArgumentParser:
        """The deepest sub-command parser ``words`` name (this parser without one)."""
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                for i, w in enumerate(words):
                    sub = action.choices.get(w)
                    if sub is not None:
                        return sub._named_sub(words[i + 1 :]) if isinstance(sub, Parser) else sub
        return self

    def _check_value(self, action: argparse.Action, value: object) -> None:
        """A word that is none of the choices (a command, a ``choices=`` option): the
        one meant first (``console.core.suggest``), then the choices."""
        choices = action.choices
        if choices is None or value in choices:
            return
        hint = suggestion(str(value), [str(c) for c in choices], "; did you mean {!r}?")
        listed = ", ".join(map(repr, choices))
        raise argparse.ArgumentError(
            action, f"invalid choice: {value!r}{hint} (choose from {listed})"
        )

    def _get_value(self, action: argparse.Action, arg_string: str) -> object:
        """A value a converter of this module refused: ``<command> <option> <value>:
        <why>; give ...``."""
        try:
            return super()._get_value(action, arg_string)
        except argparse.ArgumentError as err:
            bad = err.__context__
            if not isinstance(bad, BadValue):
                raise
            opts = action.option_strings
            name = max(opts, key=len) if opts else str(action.metavar or action.dest)
            where = f"{self.prog.removeprefix('haptable').strip()} {name}"
            raise UsageError(f"{where.strip()} {bad.shown}: {bad.why}") from None
