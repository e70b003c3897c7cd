"""Breakpoint data kept beside the signal library: what an imported haptic file's
envelope, carrier and bursts become when they are too many to write into one expression.

The library ``.../<profile>/signals.toml`` keeps the expression; ``.../<profile>/signals/
NAME.json`` keeps the curves it names with ``@NAME`` (``console.signals.breakpoints``):
``env(@NAME)`` the envelope, ``glide(100 V, @NAME)`` the carrier, ``bursts(@NAME)`` the
bursts. The file is JSON::

    {"format": "haptable-breakpoints", "version": 1, "source": "effect.haptic",
     "sha256": "<of the curves below, as canonical JSON>",
     "env": {"t_s": [...], "level": [...]},          # ratio 0..1, linear between points
     "glide": {"t_s": [...], "hz": [...]},           # carrier, linear in Hz
     "bursts": {"t_s": [...], "v": [...], "hz": [...], "dur_s": [...]}}

It is read bounded and validated like every file the console reads: a missing or
malformed file, an array of the wrong length, times that do not increase, a value out of
range or a checksum that does not match (an edit or a damaged disk: never played as it
is) is one ``UserError`` line naming the file, the key and the fix (import the haptic
file again). Numbers are written as Python writes floats, so they read back exactly.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from console.core.errors import UserError
from console.core.plain_numbers import plain_s
from console.files.atomic import write_text_atomic
from console.files.file_read import read_bytes_capped
from console.files.json_lines import decode, parse_json

FORMAT = "haptable-breakpoints"
DIR_NAME = "signals"
MAX_DATA_BYTES = 16 * 2**20
#: breakpoints a curve may hold (a 10 min file at one point every 2 ms)
MAX_POINTS = 300_000
MAX_TIME_S = 3600.0
MAX_HZ = 100_000.0
MAX_V = 10_000.0
#: key -> (its arrays, each with its range)
CURVES: dict[str, dict[str, tuple[float, float]]] = {
    "env": {"t_s": (0.0, MAX_TIME_S), "level": (0.0, 1.0)},
    "glide": {"t_s": (0.0, MAX_TIME_S), "hz": (1e-3, MAX_HZ)},
    "bursts": {
        "t_s": (0.0, MAX_TIME_S),
        "v": (-MAX_V, MAX_V),
        "hz": (1e-3, MAX_HZ),
        "dur_s": (1e-5, 10.0),
    },  # fmt: skip
}


@dataclass(frozen=True)
class Curves:
    """One data file: ``env``, ``glide``, ``bursts`` as dicts of float arrays (or None)."""

    name: str
    path: Path
    env: dict[str, np.ndarray] | None = None
    glide: dict[str, np.ndarray] | None = None
    bursts: dict[str, np.ndarray] | None = None

    def held(self) -> dict[str, dict[str, np.ndarray]]:
        """The curves the file holds, by key."""
        every = {"env": self.env, "glide": self.glide, "bursts": self.bursts}
        return {k: c for k, c in every.items() if c is not None}

    def curve(self, key: str, used_by: str) -> dict[str, np.ndarray]:
        held = self.held()
        if key not in held:
            raise UserError(
                f"{used_by}: {self.path} holds no {key!r} curve; use the parts it holds "
                f"({', '.join(held)})"
            )
        return held[key]


def data_path(library: Path, name: str) -> Path:
    """Where the data ``@name`` of the library file ``library`` lives."""
    return library.parent / DIR_NAME / f"{name}.json"


def _canonical(curves: dict[str, Any]) -> str:
    return json.dumps(curves, sort_keys=True, separators=(",", ":"))


def dump(curves: dict[str, dict[str, np.ndarray]], source: str) -> str:
    """The text of a data file holding ``curves`` (key -> array name -> values)."""
    plain = {k: {a: [float(x) for x in v] for a, v in c.items()} for k, c in curves.items()}
    digest = hashlib.sha256(_canonical(plain).encode()).hexdigest()
    doc = {"format": FORMAT, "version": 1, "source": source, "sha256": digest, **plain}
    return json.dumps(doc, separators=(",", ":")) + "\n"


def write(library: Path, name: str, curves: dict[str, dict[str, np.ndarray]], source: str) -> Path:
    """Write ``@name``'s data beside ``library`` (atomically; its folder made if needed)."""
    path = data_path(library, name)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_text_atomic(path, dump(curves, source), mode=0o644)
    except OSError as exc:
        raise UserError(f"{path}: cannot write it ({exc.strerror or exc}); give the profile's "
                        "config folder write access") from None  # fmt: skip
    return path


def _bad(path: Path, key: str, problem: str) -> UserError:
    return UserError(
        f"{path}: {key}: {problem}; import the haptic file again "
        "(haptable signals import FILE --name NAME --replace) or remove the signal"
    )


def read(path: Path, name: str) -> Curves:
    """The curves in ``path`` (one ``UserError`` line for anything missing or wrong)."""
    if not path.exists():
        raise _bad(path, f"@{name}", "the breakpoint data file is missing")
    fix = "import the haptic file again (haptable signals import FILE --replace)"
    raw = read_bytes_capped(path, what="breakpoint data", fix=fix, max_bytes=MAX_DATA_BYTES)
    doc = parse_json(decode(raw or b"", str(path), fix), str(path), fix)
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise _bad(path, "format", f"not a {FORMAT} file")
    if doc.get("version") != 1:
        raise _bad(path, "version", f"{doc.get('version')!r} is not a version this reader knows")
    unknown = [k for k in doc if k not in (*CURVES, "format", "version", "source", "sha256")]
    if unknown:
        raise _bad(path, str(unknown[0]), "unknown key")
    plain = {k: doc[k] for k in CURVES if k in doc}
    out: dict[str, dict[str, np.ndarray]] = {}
    for key, c in plain.items():
        out[key] = _curve(path, key, c)
    if hashlib.sha256(_canonical(plain).encode()).hexdigest() != doc.get("sha256"):
        raise _bad(path, "sha256", "does not match the data (edited or damaged)")
    if not out:
        raise _bad(path, "env", "missing (the file holds no curve)")
    return Curves(name, path, **out)


def _curve(path: Path, key: str, c: Any) -> dict[str, np.ndarray]:
    spec = CURVES[key]
    if not isinstance(c, dict) or set(c) != set(spec):
        raise _bad(path, key, f"give an object with the arrays {', '.join(spec)}")
    arrays, n = {}, None
    for a, (lo, hi) in spec.items():
        v = c[a]
        where = f"{key}.{a}"
        if not isinstance(v, list) or not v or len(v) > MAX_POINTS:
            raise _bad(path, where, f"give a list of 1 to {MAX_POINTS} numbers")
        if any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in v):
            raise _bad(path, where, "holds a value that is not a number")
        x = np.asarray(v, float)
        bad = ~np.isfinite(x) | (x < lo) | (x > hi)
        if bad.any():
            i = int(np.argmax(bad))
            raise _bad(path, f"{where}[{i}]", f"{v[i]!r} is outside {lo:g}..{hi:g}")
        if n is not None and x.size != n:
            raise _bad(path, where, f"{x.size} values, but {key}.t_s has {n}")
        n = x.size
        arrays[a] = x
    t = arrays["t_s"]
    need = 1 if key == "bursts" else 2
    if t.size < need:
        raise _bad(path, f"{key}.t_s", f"give at least {need} breakpoints")
    steps = np.diff(t)
    if np.any(steps <= 0 if key != "bursts" else steps < 0):
        i = int(np.argmax(steps <= 0 if key != "bursts" else steps < 0)) + 1
        raise _bad(path, f"{key}.t_s[{i}]", f"{plain_s(t[i])} is not after the time before it")
    return arrays


class LibraryData:
    """``@name`` -> ``Curves`` for the library file ``library`` (each file read once)."""

    def __init__(self, library: Path) -> None:
        self.library = Path(library)
        self._cache: dict[str, Curves] = {}

    def __call__(self, name: str) -> Curves:
        if name not in self._cache:
            self._cache[name] = read(data_path(self.library, name), name)
        return self._cache[name]


Resolver = Callable[[str], Curves]


def remove(library: Path, name: str) -> bool:
    """Remove ``@name``'s data file; whether there was one."""
    path = data_path(library, name)
    try:
        path.unlink()
    except FileNotFoundError:
        return False
    except OSError as exc:
        raise UserError(
            f"{path}: cannot remove it ({exc.strerror or exc}); remove it by hand"
        ) from None
    return True
