"""The operator's signal library: named expressions in a TOML file per profile
(``console.files.paths.profile_config_dir(profile, "signals.toml")``), beside a few built-in
signals offered read-only.

    [signals.pulse]
    expr = "seq(sine(250 Hz, 40 V, 0.5 s) * adsr(10 ms, 50 ms, 0.7, 100 ms), silence(0.2 s)) * 3"
    description = "three 250 Hz pulses"
    target = "PA,PC"       # optional: the channel it is meant for (patches or screen)

The file is read bounded (``console.files.file_read``: a regular file of at most 1 MB, so a
FIFO or ``/dev/zero`` in its place is one line, not a hang) and validated like a profile,
entry by entry: an entry that does not validate (an unknown key, a bad name, an expression
that does not parse) is one line naming the file, entry, value and fix, and the others stay
usable. A file that cannot be read as a whole is one line and is never rewritten.

Writes (``console.config.signal_library_file``) happen under a lock, re-read the file just before
each change so another console's entries are never lost, keep entries that do not validate
as they were, and replace the file atomically only once the new text reads back as itself.
Names match ``NAME_RE`` in full; with the profile's limits, ``add_signal`` refuses a signal
that could never play (``console.signals.check``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from console.config import signal_library_file as signal_file
from console.config.profile import _fmt, _printable, _where
from console.core.errors import ProfileError, UserError
from console.core.suggest import did_you_mean, suggestion
from console.files.file_read import read_toml_capped
from console.files.paths import profile_config_dir
from console.signals.breakpoint_data import LibraryData
from console.signals.check import never_plays
from console.signals.design import parse_target
from console.signals.expr import parse
from console.signals.syntax import clip

if TYPE_CHECKING:
    from console.safety import Limits

FILE_NAME = "signals.toml"
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,39}$")
ENTRY_KEYS = ("expr", "description", "target")
MAX_DESCRIPTION = 200


@dataclass(frozen=True)
class Entry:
    """A library signal; ``target`` is the channel it is meant for (``screen``, ``PA``,
    ``PA,PC`` ...: loading it sets the console's target field), "" when any."""

    name: str
    expr: str
    description: str = ""
    builtin: bool = False
    target: str = ""


#: Offered read-only: the chain's test tones as signals (``haptable play`` has them as plans).
BUILTIN: dict[str, Entry] = {
    e.name: e
    for e in (
        Entry(
            "tone-250",
            "sine(250 Hz, 20 V, 1 s) * ramp(20 ms)",
            "250 Hz, 20 V peak, 1 s (the sine-PA.. test tone)",
            True,
        ),
        Entry(
            "screen-180",
            "sine(180 Hz, 100 Vpp, 1 s) * ramp(20 ms)",
            "180 Hz, 100 Vpp, 1 s (the screen's test tone)",
            True,
            "screen",
        ),
        Entry(
            "sweep",
            "chirp(10 Hz, 625 Hz, 10 V, 3 s) * ramp(20 ms)",
            "10-625 Hz linear sweep, 10 V peak, 3 s",
            True,
        ),
        Entry(
            "bursts",
            "seq(sine(250 Hz, 10 V, 0.3 s) * ramp(20 ms), silence(0.1 s)) * 3",
            "three 250 Hz bursts of 0.3 s, 10 V peak",
            True,
        ),
    )
}


def library_path(profile_name: str) -> Path:
    """The profile's library file (it may not exist yet)."""
    return profile_config_dir(profile_name, FILE_NAME)


def _show(value: Any) -> str:
    """A value from the file or the command line as a message shows it: one line, short."""
    return _fmt(clip(value, 60) if isinstance(value, str) else value)


def check_name(name: str) -> str:
    if not isinstance(name, str) or not NAME_RE.fullmatch(name):
        raise UserError(
            f"signal name {_show(name)}: use up to 40 letters, digits, '-' or '_', starting "
            "with a letter or digit (for example tone-250)"
        )
    if name in BUILTIN:
        raise UserError(f"signal name {name!r} is a built-in signal (read-only); choose another")
    return name


def check_description(text: str) -> str:
    if not isinstance(text, str) or len(text) > MAX_DESCRIPTION or not text.isprintable():
        raise UserError(
            f"description {_show(text)}: give one printable line of at most "
            f"{MAX_DESCRIPTION} characters"
        )
    return text


@dataclass(frozen=True)
class Library:
    """What a library file holds: ``entries`` (the built-ins, then the user's that
    validate, by name), ``problems`` (name -> one line, for each entry that does not) and
    ``raw`` (the ``[signals]`` table as read: what a rewrite keeps)."""

    entries: dict[str, Entry]
    problems: dict[str, str]
    raw: dict[str, Any]


def library_data(path: Path) -> LibraryData:
    """What ``@NAME`` in the library ``path``'s signals refers to: ``signals/NAME.json``
    beside it (``console.signals.breakpoint_data``); pass it to ``parse(expr, data=...)``."""
    return LibraryData(path)


def check_target(text: str) -> str:
    """A signal's declared target as the target field writes it (``screen``, ``PA,PC``),
    "" for none; ``UserError`` when it names no channel."""
    if text == "":
        return ""
    if not isinstance(text, str):
        raise UserError(f"target = {_show(text)}: give patches (PA, PA,PC, PALL) or screen")
    return parse_target(text).label


def _entry(name: str, entry: Any, data: LibraryData | None = None) -> Entry:
    """The entry ``[signals.NAME]`` holds, or a ``UserError`` saying what is wrong."""
    check_name(name)
    if not isinstance(entry, dict):
        raise UserError(f'must be a table with expr = "..."; got {_show(entry)}')
    for key in entry:
        if key not in ENTRY_KEYS:
            guess = did_you_mean(key, ENTRY_KEYS)
            hint = f"did you mean {guess!r}?" if guess else f"known: {', '.join(ENTRY_KEYS)}"
            raise UserError(f"unknown key {_printable(clip(key, 60))!r} ({hint})")
    expr = entry.get("expr")
    if not isinstance(expr, str):
        raise UserError(
            f"expr = {_show(expr) if 'expr' in entry else '(missing)'}: give the signal as a "
            'string, e.g. expr = "sine(250 Hz, 20 V, 1 s) * ramp(10 ms)"'
        )
    try:
        parse(expr, data=data)
    except UserError as exc:
        raise UserError(f"expr = {_show(expr)}: {exc}") from None
    desc = entry.get("description", "")
    check_description(desc)
    try:
        target = check_target(entry.get("target", ""))
    except UserError as exc:
        raise UserError(f"target = {_show(entry.get('target'))}: {exc}") from None
    return Entry(name, expr, desc, target=target)


def read_library(path: Path) -> Library:
    """The library at ``path`` (none when it does not exist). A file that cannot be read
    as a whole is one ``ProfileError``; an entry that does not validate is left out of
    ``entries`` with its line in ``problems``, the others stay usable."""
    where = _where(path)
    raw = read_toml_capped(
        path,
        what="signal library",
        fix="give the library as a TOML file (or remove it: the built-ins stay)",
        max_bytes=signal_file.MAX_LIBRARY_BYTES,
        error=ProfileError,
        missing_ok=True,
    )
    raw = {} if raw is None else raw
    for key in raw:
        if key != "signals":
            raise ProfileError(
                f"{where}: unknown key {_printable(clip(key, 60))!r} at the top; a signal "
                "library holds [signals.NAME] tables only"
            )
    table = raw.get("signals", {})
    if not isinstance(table, dict):
        raise ProfileError(f"{where}: signals = {_show(table)}: write [signals.NAME] tables")
    if len(table) > signal_file.MAX_ENTRIES:
        raise ProfileError(
            f"{where}: {len(table)} signals, more than the {signal_file.MAX_ENTRIES} a library "
            "keeps; move some to another file"
        )
    user: dict[str, Entry] = {}
    problems: dict[str, str] = {}
    data = library_data(path)
    for name, entry in table.items():
        try:
            user[name] = _entry(name, entry, data)
        except UserError as exc:
            problems[name] = (
                f"{where}: [signals.{_fmt_key(name)}] {exc}; or remove the entry "
                "(haptable signals rm)"
            )
    return Library({**BUILTIN, **dict(sorted(user.items()))}, problems, table)


def _fmt_key(name: str) -> str:
    return name if NAME_RE.fullmatch(name) else _show(name)


def load_library(path: Path) -> dict[str, Entry]:
    """Built-in signals, then the user's that validate (sorted by name)."""
    return read_library(path).entries


def get_signal(path: Path, name: str) -> Entry:
    lib = read_library(path)
    if name in lib.problems:
        raise UserError(lib.problems[name])
    if name not in lib.entries:
        hint = suggestion(name, lib.entries, "did you mean {!r}? ")
        raise UserError(
            f"no signal {name!r} in {_where(path)}; {hint}`haptable signals list` shows them"
        )
    return lib.entries[name]


def add_signal(
    path: Path,
    name: str,
    expr: str,
    description: str = "",
    *,
    replace: bool = False,
    limits: Limits | None = None,
    target: str = "",
) -> Entry:
    """Save ``name`` = ``expr`` (meant for ``target``, "" for any channel) keeping every
    other entry (those that do not validate too). ``expr`` must parse and, with
    ``limits``, be able to play on some target."""
    check_name(name)
    check_description(description)
    target = check_target(target)
    node = parse(expr, data=library_data(path))
    if limits is not None and (why := never_plays(node, limits)) is not None:
        raise UserError(f"signal {name!r} can never play on this table: {why}; nothing saved")
    with signal_file.locked(path):
        lib = read_library(path)
        old = lib.raw.get(name)
        same = old is not None and old.get("expr") == expr and old.get("target", "") == target
        if old is not None and not replace and (name in lib.problems or not same):
            raise UserError(
                f"signal {name!r} is already in {_where(path)}; choose another name or "
                "replace it (--replace)"
            )
        entry = {
            "expr": expr,
            **({"description": description} if description else {}),
            **({"target": target} if target else {}),
        }
        signal_file.write(path, dict(sorted({**lib.raw, name: entry}.items())))
    return Entry(name, expr, description, target=target)


def remove_signal(path: Path, name: str) -> Any:
    """Remove ``name`` (also an entry that does not validate, such as one written by hand
    under a built-in's name), keeping every other one. Returns its table as the file had
    it (``restore_signal`` puts it back)."""
    with signal_file.locked(path):
        lib = read_library(path)
        if name in BUILTIN and name not in lib.raw:
            raise UserError(f"{name!r} is a built-in signal (read-only); it cannot be removed")
        if name not in lib.raw:
            raise UserError(f"no signal {name!r} in {_where(path)} to remove")
        signal_file.write(path, {k: v for k, v in lib.raw.items() if k != name})
        return lib.raw[name]


def restore_signal(path: Path, name: str, raw: Any) -> None:
    """Put back ``name`` as ``remove_signal`` returned it (an undo), keeping every other
    entry; refused when an entry of that name was saved since."""
    with signal_file.locked(path):
        lib = read_library(path)
        if name in lib.raw:
            raise UserError(f"signal {name!r} is in {_where(path)} again; nothing restored")
        signal_file.write(path, dict(sorted({**lib.raw, name: raw}.items())))
