"""The operator's signal library: named expressions in a TOML file per profile
(``console.paths.profile_config_dir(profile, "signals.toml")``), beside a few built-in
signals offered read-only.

    [signals.pulse]
    expr = "seq(sine(250 Hz, 40 V, 0.5 s) * adsr(10 ms, 50 ms, 0.7, 100 ms), silence(0.2 s)) * 3"
    description = "three 250 Hz pulses"

The file is validated like a profile (unknown keys, bad values and expressions that do not
parse are refused with one line naming the file, key, value and fix) and written
atomically (a temporary file renamed over it, under a lock), re-read just before each
change so another console's entries are never lost. A file that does not validate is never
rewritten: the operator's entries stay as they were.
"""

from __future__ import annotations

import contextlib
import difflib
import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from console.atomic import write_text_atomic
from console.errors import ProfileError, UserError
from console.paths import profile_config_dir
from console.profile import _fmt, _printable, _where, parse_toml
from console.signal_expr import parse

FILE_NAME = "signals.toml"
NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]{0,39}$")
ENTRY_KEYS = ("expr", "description")
MAX_DESCRIPTION = 200


@dataclass(frozen=True)
class Entry:
    name: str
    expr: str
    description: str = ""
    builtin: bool = False


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


def check_name(name: str) -> str:
    if not isinstance(name, str) or not NAME_RE.match(name):
        raise UserError(
            f"signal name {_fmt(name)}: use up to 40 letters, digits, '-' or '_', starting "
            "with a letter or digit"
        )
    if name in BUILTIN:
        raise UserError(f"signal name {name!r} is a built-in signal (read-only); choose another")
    return name


def check_description(text: str) -> str:
    if not isinstance(text, str) or len(text) > MAX_DESCRIPTION or not text.isprintable():
        raise UserError(
            f"description {_fmt(text)}: give one printable line of at most "
            f"{MAX_DESCRIPTION} characters"
        )
    return text


def _entries(path: Path) -> dict[str, Entry]:
    """The user's entries in ``path`` (none when it does not exist), validated."""
    if not path.exists():
        return {}
    where = _where(path)
    raw = parse_toml(path)
    for key in raw:
        if key != "signals":
            raise ProfileError(
                f"{where}: unknown key {_printable(key)!r} at the top; a signal library holds "
                "[signals.NAME] tables only"
            )
    table = raw.get("signals", {})
    if not isinstance(table, dict):
        raise ProfileError(f"{where}: signals = {_fmt(table)}: write [signals.NAME] tables")
    out: dict[str, Entry] = {}
    for name, entry in table.items():
        label = f"[signals.{_printable(name)}]"
        try:
            check_name(name)
        except UserError as exc:
            raise ProfileError(f"{where}: {label} {exc}") from None
        if not isinstance(entry, dict):
            raise ProfileError(
                f'{where}: {label} must be a table with expr = "..."; got {_fmt(entry)}'
            )
        for key in entry:
            if key not in ENTRY_KEYS:
                guess = difflib.get_close_matches(key, ENTRY_KEYS, n=1)
                hint = f"did you mean {guess[0]!r}?" if guess else f"known: {', '.join(ENTRY_KEYS)}"
                raise ProfileError(f"{where}: {label} unknown key {_printable(key)!r} ({hint})")
        expr = entry.get("expr")
        if not isinstance(expr, str):
            raise ProfileError(
                f"{where}: {label} expr = {_fmt(expr) if 'expr' in entry else '(missing)'}: "
                'give the signal as a string, e.g. expr = "sine(250 Hz, 20 V, 1 s) * ramp(10 ms)"'
            )
        try:
            parse(expr)
        except UserError as exc:
            raise ProfileError(f"{where}: {label} expr = {_fmt(expr)}: {exc}") from None
        desc = entry.get("description", "")
        try:
            check_description(desc)
        except UserError as exc:
            raise ProfileError(f"{where}: {label} {exc}") from None
        out[name] = Entry(name, expr, desc)
    return out


def load_library(path: Path) -> dict[str, Entry]:
    """Built-in signals, then the user's (sorted by name)."""
    user = _entries(path)
    return {**BUILTIN, **dict(sorted(user.items()))}


def get_signal(path: Path, name: str) -> Entry:
    lib = load_library(path)
    if name not in lib:
        guess = difflib.get_close_matches(name, list(lib), n=1)
        hint = f"did you mean {guess[0]!r}? " if guess else ""
        raise UserError(
            f"no signal {name!r} in {_where(path)}; {hint}`haptable signals list` shows them"
        )
    return lib[name]


def _toml(entries: dict[str, Entry]) -> str:
    lines = [
        "# HapTable signal library: named signals in the console's expression syntax.",
        "# Written by `haptable signals add` and the console's Signals screen; edits by hand",
        "# are kept (comments are not).",
    ]
    for e in entries.values():
        lines += ["", f"[signals.{e.name}]", f"expr = {json.dumps(e.expr, ensure_ascii=False)}"]
        if e.description:
            lines.append(f"description = {json.dumps(e.description, ensure_ascii=False)}")
    return "\n".join(lines) + "\n"


@contextlib.contextmanager
def _locked(path: Path) -> Iterator[None]:
    path.parent.mkdir(parents=True, exist_ok=True)
    import fcntl

    with open(path.with_name(path.name + ".lock"), "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def _write(path: Path, entries: dict[str, Entry]) -> None:
    write_text_atomic(path, _toml(entries))


def add_signal(
    path: Path, name: str, expr: str, description: str = "", *, replace: bool = False
) -> Entry:
    """Save ``name`` = ``expr`` (checked: it must parse) keeping every other entry."""
    check_name(name)
    check_description(description)
    parse(expr)
    try:
        with _locked(path):
            entries = _entries(path)
            if name in entries and not replace and entries[name].expr != expr:
                raise UserError(
                    f"signal {name!r} is already in {_where(path)}; choose another name or "
                    "replace it (--replace)"
                )
            entries[name] = Entry(name, expr, description)
            _write(path, dict(sorted(entries.items())))
    except OSError as exc:
        raise UserError(f"{_where(path)}: cannot write: {exc.strerror or exc}") from None
    return entries[name]


def remove_signal(path: Path, name: str) -> None:
    if name in BUILTIN:
        raise UserError(f"{name!r} is a built-in signal (read-only); it cannot be removed")
    try:
        with _locked(path):
            entries = _entries(path)
            if name not in entries:
                raise UserError(f"no signal {name!r} in {_where(path)} to remove")
            del entries[name]
            _write(path, entries)
    except OSError as exc:
        raise UserError(f"{_where(path)}: cannot write: {exc.strerror or exc}") from None
