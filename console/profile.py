"""TOML profiles -> validated settings, with one-line errors naming file, key and value.

A profile is found by path, or by name in ``$HAPTABLE_PROFILES``,
``~/.config/haptable/profiles`` and the project's ``profiles/`` folder. Sections are
declared by plugins (``haptable_profile_sections``); the core declares its own in
``console.core_plugin``.
"""

from __future__ import annotations

import difflib
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from console.errors import ProfileError
from console.schema import Field, check

if TYPE_CHECKING:
    from console.plugins import Plugins

DEFAULT_PROFILE = "sim"
PROJECT_PROFILES = Path(__file__).resolve().parent.parent / "profiles"


def search_dirs() -> list[Path]:
    dirs = []
    if env := os.environ.get("HAPTABLE_PROFILES"):
        dirs += [Path(p) for p in env.split(os.pathsep) if p]
    dirs.append(Path.home() / ".config" / "haptable" / "profiles")
    dirs.append(PROJECT_PROFILES)
    return dirs


def find_profile(name_or_path: str | os.PathLike | None) -> Path:
    """Resolve ``--profile`` (a name like ``sim`` or a path to a .toml file)."""
    raw = str(name_or_path or os.environ.get("HAPTABLE_PROFILE") or DEFAULT_PROFILE)
    p = Path(raw).expanduser()
    if p.suffix == ".toml" or os.sep in raw:
        if p.is_file():
            return p.resolve()
        raise ProfileError(f"{raw}: profile file not found; give an existing .toml path or a name")
    for d in search_dirs():
        cand = d / f"{raw}.toml"
        if cand.is_file():
            return cand.resolve()
    known = sorted({q.stem for d in search_dirs() if d.is_dir() for q in d.glob("*.toml")})
    guess = difflib.get_close_matches(raw, known, n=1)
    hint = f" (did you mean {guess[0]!r}?)" if guess else ""
    raise ProfileError(
        f"profile {raw!r} not found{hint}; known profiles: {', '.join(known) or 'none'} "
        f"(searched {', '.join(str(d) for d in search_dirs())})"
    )


@dataclass(frozen=True)
class Profile:
    """Validated settings. ``get("audio.sample_rate_hz")``; defaults are filled in."""

    name: str
    path: Path
    data: dict[str, Any] = field(repr=False)

    def get(self, dotted: str, default: Any = None) -> Any:
        node: Any = self.data
        for part in dotted.split("."):
            if not isinstance(node, dict) or part not in node:
                return default
            node = node[part]
        return node

    def section(self, name: str) -> dict[str, Any]:
        return dict(self.data.get(name, {}))

    def items(self, name: str) -> dict[str, dict[str, Any]]:
        """Named sub-tables of a per-item section (``[patches.PA]`` ...)."""
        return {k: dict(v) for k, v in self.data.get(name, {}).items()}

    def resolve(self, rel: str | os.PathLike) -> Path:
        """A path from the profile, relative to the profile's folder."""
        p = Path(rel).expanduser()
        return p if p.is_absolute() else (self.path.parent / p).resolve()


def _where(path: Path) -> str:
    try:
        return str(path.relative_to(Path.cwd()))
    except ValueError:
        return str(path)


def _fmt(value: Any) -> str:
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)


def _validate_table(
    where: str, label: str, table: Any, fields: dict[str, Field], base: Path
) -> dict[str, Any]:
    if not isinstance(table, dict):
        raise ProfileError(f"{where}: [{label}] must be a table, got {_fmt(table)}")
    out: dict[str, Any] = {}
    for key, value in table.items():
        if key not in fields:
            guess = difflib.get_close_matches(key, list(fields), n=1)
            hint = f"did you mean {guess[0]!r}?" if guess else f"known keys: {', '.join(fields)}"
            raise ProfileError(f"{where}: [{label}] unknown key {key!r} ({hint})")
        f = fields[key]
        ok, norm = check(f, value)
        if not ok:
            raise ProfileError(
                f"{where}: [{label}] {key} = {_fmt(value)}: expected {f.allowed()}"
                + (f" ({f.help})" if f.help else "")
            )
        if f.kind == "path" and norm and f.must_exist:
            p = Path(norm).expanduser()
            p = p if p.is_absolute() else base / p
            if not p.exists():
                raise ProfileError(
                    f"{where}: [{label}] {key} = {_fmt(value)}: file not found at {p}; "
                    f"fix the path (relative to the profile's folder) or remove the key"
                )
        out[key] = norm
    for key, f in fields.items():
        if key in out:
            continue
        if f.required:
            raise ProfileError(
                f"{where}: [{label}] missing key {key!r}: add {key} = <{f.allowed()}>"
            )
        out[key] = f.default
    return out


def validate(raw: dict[str, Any], path: Path, plugins: Plugins) -> dict[str, Any]:
    """Check every section and key against the plugins' declared schemas."""
    where = _where(path)
    sections = plugins.sections
    data: dict[str, Any] = {}
    for name, table in raw.items():
        if name not in sections:
            guess = difflib.get_close_matches(name, list(sections), n=1)
            hint = f"did you mean [{guess[0]}]?" if guess else "no loaded plugin declares it"
            raise ProfileError(f"{where}: unknown section [{name}] ({hint})")
        fields, per_item, _help, _owner = sections[name]
        if per_item:
            if not isinstance(table, dict):
                raise ProfileError(f"{where}: [{name}] must hold named tables like [{name}.X]")
            data[name] = {
                item: _validate_table(where, f"{name}.{item}", sub, fields, path.parent)
                for item, sub in table.items()
            }
        else:
            data[name] = _validate_table(where, name, table, fields, path.parent)
    for name, (fields, per_item, _help, _owner) in sections.items():
        if name not in data:
            data[name] = {} if per_item else _validate_table(where, name, {}, fields, path.parent)
    return data


def check_drivers(profile: Profile, plugins: Plugins) -> None:
    """Every ``driver = "..."`` must name a registered driver of its kind."""
    where = _where(profile.path)
    for section, kind in (
        ("camera", "camera"),
        ("audio", "audio_output"),
        ("relays", "relay_board"),
        ("vibrometer", "vibrometer"),
    ):
        name = profile.get(f"{section}.driver")
        if name is None:
            continue
        regs = plugins.of(kind)
        if name not in regs:
            guess = difflib.get_close_matches(name, list(regs), n=1)
            hint = f"did you mean {guess[0]!r}? " if guess else ""
            raise ProfileError(
                f"{where}: [{section}] driver = {_fmt(name)}: unknown {kind.replace('_', ' ')} "
                f"driver; {hint}available: {', '.join(sorted(regs)) or 'none'}"
            )


def load_profile(
    name_or_path: str | os.PathLike | None = None, plugins: Plugins | None = None
) -> Profile:
    """Find, parse and validate a profile. Raises ``ProfileError`` with one line."""
    if plugins is None:
        from console.plugins import load_plugins

        plugins = load_plugins()
    path = find_profile(name_or_path)
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as exc:
        raise ProfileError(f"{_where(path)}: not valid TOML: {exc}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ProfileError(f"{_where(path)}: cannot read: {exc}") from None
    profile = Profile(name=path.stem, path=path, data=validate(raw, path, plugins))
    check_drivers(profile, plugins)
    from console.core_plugin import check_consistency

    check_consistency(profile)
    return profile
