"""Every directory HapTable writes, by one rule each.

=============  ========================  =================================  ======================
function       override                  XDG base                           default
=============  ========================  =================================  ======================
config_dir     ``$HAPTABLE_CONFIG_DIR``  ``$XDG_CONFIG_HOME/haptable``      ``~/.config/haptable``
state_dir      ``$HAPTABLE_STATE_DIR``   ``$XDG_STATE_HOME/haptable``       ``~/.local/state/haptable``
cache_dir      ``$HAPTABLE_CACHE_DIR``   ``$XDG_CACHE_HOME/haptable``       ``~/.cache/haptable``
data_dir       ``$HAPTABLE_DATA_DIR``    ``$XDG_DATA_HOME/haptable``        ``~/.local/share/haptable``
runtime_dir    --                        ``$XDG_RUNTIME_DIR/haptable``      ``/tmp/haptable-<uid>``
=============  ========================  =================================  ======================

An override names the directory itself (no ``haptable`` appended). An empty or relative XDG
variable is ignored, as the XDG base-directory spec says. These functions only compute paths;
they create nothing. The runtime directory holds sockets and the process registry, so its
users take it from ``console.kernel.private_dir.runtime_dir``, which creates it 0700 and
refuses one that is not private.
"""

from __future__ import annotations

import os
from pathlib import Path

APP = "haptable"


def _xdg(var: str, *default: str) -> Path:
    raw = os.environ.get(var, "")
    return Path(raw) if raw and os.path.isabs(raw) else Path.home().joinpath(*default)


def _dir(override: str, xdg_var: str, default: tuple[str, ...], parts: tuple[str, ...]) -> Path:
    env = os.environ.get(override, "")
    base = Path(env).expanduser() if env else _xdg(xdg_var, *default) / APP
    return base.joinpath(*parts)


def config_dir(*parts: str) -> Path:
    """Settings the operator writes (profiles): ``$HAPTABLE_CONFIG_DIR`` or
    ``$XDG_CONFIG_HOME/haptable``, then ``parts`` below it."""
    return _dir("HAPTABLE_CONFIG_DIR", "XDG_CONFIG_HOME", (".config",), parts)


def state_dir(*parts: str) -> Path:
    """What the console keeps between runs (its log): ``$HAPTABLE_STATE_DIR`` or
    ``$XDG_STATE_HOME/haptable``, then ``parts`` below it."""
    return _dir("HAPTABLE_STATE_DIR", "XDG_STATE_HOME", (".local", "state"), parts)


def cache_dir(*parts: str) -> Path:
    """What can be computed again (tables, measured maps, features): ``$HAPTABLE_CACHE_DIR``
    or ``$XDG_CACHE_HOME/haptable``, then ``parts`` below it."""
    return _dir("HAPTABLE_CACHE_DIR", "XDG_CACHE_HOME", (".cache",), parts)


def data_dir(*parts: str) -> Path:
    """What the operator records and keeps (datasets): ``$HAPTABLE_DATA_DIR`` or
    ``$XDG_DATA_HOME/haptable``, then ``parts`` below it."""
    return _dir("HAPTABLE_DATA_DIR", "XDG_DATA_HOME", (".local", "share"), parts)


def runtime_dir() -> Path:
    """Where sockets, the process registry and run logs go: ``$XDG_RUNTIME_DIR/haptable``
    or, without it, ``/tmp/haptable-<uid>``. Unchecked and not created: use
    ``console.kernel.private_dir.runtime_dir()``, which is."""
    base = os.environ.get("XDG_RUNTIME_DIR")
    return Path(base) / APP if base else Path(f"/tmp/{APP}-{os.getuid()}")


def _profile_part(name: str) -> str:
    """A profile's name as one safe path component (``sim``, ``haptable-lab``)."""
    safe = "".join(c if c.isalnum() or c in "-_." else "_" for c in str(name)).strip(".")
    # "profiles" is the folder of profile files beside these
    return {"": "default", "profiles": "profiles_"}.get(safe, safe)


def profile_config_dir(profile_name: str, *parts: str) -> Path:
    """Settings the operator edits for one profile (its signal library, camera settings,
    tuned thresholds): ``config_dir(<profile name>, ...)``, never the repository's
    ``profiles/``."""
    return config_dir(_profile_part(profile_name), *parts)


def profile_state_dir(profile_name: str, *parts: str) -> Path:
    """What the console produces for one profile and keeps (calibrations, trained models):
    ``state_dir(<profile name>, ...)``."""
    return state_dir(_profile_part(profile_name), *parts)


def _resolved(p: Path) -> Path:
    """``p.resolve()``, or ``p`` where it cannot be (a symlink loop, a folder gone)."""
    try:
        return p.resolve()
    except (OSError, RuntimeError):
        return p


def shown_path(p: str | os.PathLike) -> str:
    """``p`` as a message or a screen shows it: as given when relative or starting with
    ``~`` (what was typed, read where it was typed); under the home folder as ``~/...``;
    else absolute. Never made relative to the working folder: ``home/.config/...`` read
    from another folder, or by a person who never typed it, names nothing they know."""
    raw = os.fspath(p)
    path = Path(raw)
    if not raw or raw.startswith("~") or not path.is_absolute():
        return raw
    home = Path.home()
    if home != Path(home.anchor):  # a home of / would put ~ before every path
        for h in dict.fromkeys((home, _resolved(home))):
            for q in dict.fromkeys((path, _resolved(path))):
                try:
                    rest = q.relative_to(h)
                except ValueError:
                    continue
                return "~" if not rest.parts else f"~/{rest}"
    return raw
