"""TOML profiles -> validated settings, with one-line errors naming file, key and value.

A profile is found by path, or by name in ``$HAPTABLE_PROFILES``,
``profiles`` in the config directory (``console.files.paths``: ``~/.config/haptable/profiles``)
and the project's ``profiles/`` folder. Sections are
declared by plugins (``haptable_profile_sections``); the core declares its own in
``console.config.core_sections``.

What the operator saves from the console (the sound card, the relay board, later the
camera's settings) goes to the profile's override file,
``console.files.paths.profile_config_dir(<name>, "overrides.toml")``, never to the profile
itself: it is merged over the profile at load and validated exactly like it
(``save_overrides`` writes it atomically, keeping every other key).
"""

from __future__ import annotations

import copy
import dataclasses
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from console.config.core_sections import check_consistency
from console.core.errors import ProfileError, UserError
from console.core.schema import Field, check, explain
from console.core.suggest import did_you_mean, suggestion
from console.files import paths
from console.files.atomic import write_text_atomic
from console.files.file_read import parse_toml_text, read_text_capped
from console.files.profile_paths import (  # noqa: F401 - re-exported
    DEFAULT_PROFILE,
    PROJECT_PROFILES,
    find_profile,
    search_dirs,
)

if TYPE_CHECKING:
    from console.config.plugins import Plugins

#: the file of the operator's saved settings in each profile's config directory
OVERRIDES_FILE = "overrides.toml"
#: A profile is a page of settings; anything larger is refused before it is read.
MAX_PROFILE_BYTES = 1024 * 1024


@dataclass(frozen=True)
class Profile:
    """Validated settings. ``get("audio.sample_rate_hz")``; defaults are filled in."""

    name: str
    path: Path
    data: dict[str, Any] = field(repr=False)
    #: the override file merged over the profile at load (None: there was none)
    overrides: Path | None = None

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
    """``path`` in a message: ``console.files.paths.shown_path``."""
    return paths.shown_path(path)


def _fmt(value: Any) -> str:
    if isinstance(value, str):
        return '"' + _printable(value) + '"'
    if isinstance(value, bool):
        return "true" if value else "false"
    text = repr(value)
    return text if len(text) <= 80 else text[:60] + f"... ({len(text)} characters)"


def _printable(name: str) -> str:
    """A key, section or string value as it can be shown on one line (control and
    invisible characters escaped, as Python writes them)."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in name)


def _validate_table(
    where: str,
    label: str,
    table: Any,
    fields: dict[str, Field],
    base: Path,
    partial: bool = False,
) -> dict[str, Any]:
    label = _printable(label)
    if not isinstance(table, dict):
        raise ProfileError(
            f"{where}: [{label}] must be a table, got {_fmt(table)}; write it as [{label}] "
            "with its keys on the lines below"
        )
    out: dict[str, Any] = {}
    for key, value in table.items():
        if key not in fields:
            guess = did_you_mean(key, fields)
            hint = f"did you mean {guess!r}?" if guess else f"known keys: {', '.join(fields)}"
            raise ProfileError(f"{where}: [{label}] unknown key {key!r} ({hint})")
        f = fields[key]
        ok, norm = check(f, value)
        if not ok:
            raise ProfileError(
                f"{where}: [{label}] {key} = {_fmt(value)}: {explain(f, value)}"
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
        if key in out or partial:
            continue
        if f.required:
            raise ProfileError(
                f"{where}: [{label}] missing key {key!r}: add {key} = <{f.allowed()}>"
            )
        out[key] = f.default
    return out


def validate(
    raw: dict[str, Any],
    path: Path,
    plugins: Plugins,
    *,
    partial: bool = False,
    base: Path | None = None,
) -> dict[str, Any]:
    """Check every section and key against the plugins' declared schemas. ``partial``
    (an override file) checks what is there and fills in nothing; relative paths are
    relative to ``base`` (the profile's folder; default: ``path``'s)."""
    where = _where(path)
    folder = base if base is not None else path.parent
    sections = plugins.sections
    data: dict[str, Any] = {}
    for name, table in raw.items():
        if name not in sections:
            guess = did_you_mean(name, sections)
            hint = f"did you mean [{guess}]?" if guess else "no loaded plugin declares it"
            raise ProfileError(f"{where}: unknown section [{_printable(name)}] ({hint})")
        fields, per_item, _help, _owner = sections[name]
        if per_item:
            if not isinstance(table, dict):
                raise ProfileError(f"{where}: [{name}] must hold named tables like [{name}.X]")
            data[name] = {
                item: _validate_table(where, f"{name}.{item}", sub, fields, folder, partial)
                for item, sub in table.items()
            }
        else:
            data[name] = _validate_table(where, name, table, fields, folder, partial)
    if partial:
        return data
    for name, (fields, per_item, _help, _owner) in sections.items():
        if name not in data:
            data[name] = {} if per_item else _validate_table(where, name, {}, fields, folder)
    return data


def check_drivers(profile: Profile, plugins: Plugins) -> None:
    """Every ``driver = "..."`` must name a registered driver of its kind."""
    where = _where(profile.path)
    for section, kind in (
        ("camera", "camera"),
        ("audio", "audio_output"),
        ("relays", "relay_board"),
        ("vibrometer", "vibrometer"),
        ("projector", "projector"),
    ):
        name = profile.get(f"{section}.driver")
        if name is None:
            continue
        regs = plugins.of(kind)
        if name not in regs:
            hint = suggestion(name, regs, "did you mean {!r}? ")
            raise ProfileError(
                f"{where}: [{section}] driver = {_fmt(name)}: unknown {kind.replace('_', ' ')} "
                f"driver; {hint}available: {', '.join(sorted(regs)) or 'none'}"
            )


def check_sections(profile: Profile, plugins: Plugins) -> None:
    """Each plugin's check across keys (``register(..., check=)``), its ``UserError``
    as a ``ProfileError`` naming the file."""
    for fn in plugins.section_checks.values():
        try:
            fn(profile)
        except ProfileError:
            raise
        except UserError as exc:
            raise ProfileError(f"{_where(profile.path)}: {exc}") from None


def _file_words(path: Path) -> tuple[str, str]:
    """(what, fix) naming a profile or its override file in a message."""
    if path.name == OVERRIDES_FILE:
        return "settings file", (
            "the settings the console saved there (device picks) are not loaded; make it a "
            "regular file or remove it"
        )
    return "profile", "give the profile's .toml file"


def _read_settings_file(path: Path) -> str:
    """A profile's or an override file's text, after checking it is a regular file
    (not a folder, a FIFO that would block, a device that never ends, a dangling link)
    of at most ``MAX_PROFILE_BYTES``, and UTF-8 (``console.files.file_read``)."""
    what, fix = _file_words(path)
    try:
        os.stat(path)
    except FileNotFoundError:
        if path.is_symlink():
            raise ProfileError(
                f"{_where(path)}: a link to {os.readlink(path)}, which does not exist; {fix}"
            ) from None
    except OSError:
        pass  # a link loop, a folder we may not enter: named below
    text = read_text_capped(
        path, what=what, fix=fix, max_bytes=MAX_PROFILE_BYTES, error=ProfileError
    )
    assert text is not None
    return text


def parse_toml(path: Path) -> dict[str, Any]:
    """The profile file's TOML, refused with one line when not a regular file, too
    large, not UTF-8, not TOML or nested too deeply (``file_read.parse_toml_text``)."""
    return parse_toml_text(
        _read_settings_file(path),
        where=_where(path),
        what=_file_words(path)[0],
        error=ProfileError,
        levels="at most two levels ([section] and [section.item])",
    )


def load_profile(name_or_path: str | os.PathLike | None, plugins: Plugins) -> Profile:
    """Find, parse and validate a profile (``None``: the default one) against the
    sections ``plugins`` declare, with its override file (``overrides_path``) merged over
    it. Raises ``ProfileError`` with one line."""
    path = find_profile(name_or_path)
    over_path = overrides_path(path.stem)
    return _build(path, parse_toml(path), read_overrides(over_path, path, plugins), plugins)


def _build(path: Path, raw: dict[str, Any], over: dict[str, Any], plugins: Plugins) -> Profile:
    """The profile of file ``path`` (its TOML ``raw``) with the checked overrides ``over``
    merged over it, validated; a check across keys that fails only because of the
    overrides names the override file too."""
    over_path = overrides_path(path.stem)
    profile = Profile(
        name=path.stem,
        path=path,
        data=validate(_merge(raw, over) if over else raw, path, plugins),
        overrides=over_path if over else None,
    )
    check_drivers(profile, plugins)
    try:
        check_consistency(profile)
        check_sections(profile, plugins)
    except ProfileError as exc:
        if not over:
            raise
        raise ProfileError(
            f"{exc} (with the overrides saved in {_where(over_path)}: change that key there "
            "or remove it)"
        ) from None
    return profile


# --------------------------------------------------------------------------- overrides
def overrides_path(profile_name: str) -> Path:
    """Where the operator's saved settings for profile ``profile_name`` live."""
    return paths.profile_config_dir(profile_name, OVERRIDES_FILE)


def overrides_keep(profile: Profile, keys: list[str]) -> bool:
    """Whether ``profile``'s overrides file keeps any of ``keys`` (``"vision.x"``): a
    save would replace them. A missing or unreadable file keeps none."""
    try:
        raw = parse_toml(overrides_path(profile.name))
    except (OSError, UserError):
        return False
    for dotted in keys:
        node: Any = raw
        for part in dotted.split("."):
            node = node.get(part) if isinstance(node, dict) else None
        if node is not None:
            return True
    return False


def _merge(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    """``over`` merged into ``base`` table by table (``over``'s values win)."""
    out = dict(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


def read_overrides(path: Path, profile_path: Path, plugins: Plugins) -> dict[str, Any]:
    """The override file's raw tables ({} when there is none), each key checked like the
    profile's (a bad one: one line naming this file, the key and the fix)."""
    if not os.path.lexists(path):
        return {}
    raw = parse_toml(path)  # a folder, FIFO or dangling link there: one line, not ignored
    data = validate(raw, path, plugins, partial=True, base=profile_path.parent)
    check_drivers(Profile(name=profile_path.stem, path=path, data=data), plugins)
    return raw


def save_overrides(profile: Profile, settings: dict[str, Any], plugins: Plugins) -> Path:
    """Save ``settings`` (``{"audio.device": "...", ...}``) to ``profile``'s override
    file, keeping every other key (and comment) in it, checked like the profile before
    anything is written; written atomically. Returns the file's path."""
    import tomlkit  # third-party, loaded only when settings are saved

    path = overrides_path(profile.name)
    if os.path.lexists(path):
        # a broken file, a folder, a FIFO or a dangling link is refused with its line,
        # never overwritten; a link to a file is written through (the link stays)
        parse_toml(path)
        doc = tomlkit.parse(path.read_text(encoding="utf-8"))
        path = path.resolve()
    else:
        doc = tomlkit.document()
    for dotted, value in settings.items():
        *tables, key = dotted.split(".")
        if not tables:
            raise ProfileError(f"{dotted!r}: a setting is named section.key")
        node: Any = doc
        for t in tables:
            if t not in node:
                node[t] = tomlkit.table()
            node = node[t]
        node[key] = value
    text = tomlkit.dumps(doc)
    try:
        new_raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:  # a value TOML cannot hold
        raise ProfileError(f"{_where(path)}: cannot save {settings}: {exc}") from None
    data = validate(new_raw, path, plugins, partial=True, base=profile.path.parent)
    check_drivers(Profile(name=profile.name, path=path, data=data), plugins)
    _build(profile.path, parse_toml(profile.path), new_raw, plugins)  # the next load works
    try:
        write_text_atomic(path, text)
    except OSError as exc:
        raise ProfileError(
            f"{_where(path)}: cannot save the profile's settings: {exc.strerror or exc}; "
            "check the config directory is writable ($HAPTABLE_CONFIG_DIR)"
        ) from None
    return path


def with_settings(profile: Profile, settings: dict[str, Any]) -> Profile:
    """``profile`` with the dotted ``settings`` set (a trial: nothing is written)."""
    data = copy.deepcopy(profile.data)
    for dotted, value in settings.items():
        *path, last = dotted.split(".")
        node = data
        for part in path:
            node = node.setdefault(part, {})
        node[last] = value
    return dataclasses.replace(profile, data=data)
