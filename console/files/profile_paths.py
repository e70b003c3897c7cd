"""Where profiles are found: by path, or by name in ``$HAPTABLE_PROFILES``, ``profiles``
in the config directory (``~/.config/haptable/profiles``) and the project's ``profiles/``.

Standard library only: `haptable estop` finds the tables it latches from here without
loading a profile (``console.kernel.tables``).
"""

from __future__ import annotations

import os
from pathlib import Path

from console.core.errors import ProfileError
from console.files import paths

DEFAULT_PROFILE = "sim"
PROJECT_PROFILES = Path(__file__).resolve().parents[2] / "profiles"


def search_dirs() -> list[Path]:
    """The folders a profile name is looked up in, first match wins."""
    dirs = []
    if env := os.environ.get("HAPTABLE_PROFILES"):
        dirs += [Path(p) for p in env.split(os.pathsep) if p]
    dirs.append(paths.config_dir("profiles"))
    dirs.append(PROJECT_PROFILES)
    return dirs


def default_profile_arg() -> str:
    """The profile a command uses without ``--profile``."""
    return os.environ.get("HAPTABLE_PROFILE") or DEFAULT_PROFILE


def find_profile(name_or_path: str | os.PathLike | None) -> Path:
    """Resolve ``--profile`` (a name like ``sim`` or a path to a .toml file)."""
    raw = str(name_or_path or default_profile_arg())
    p = Path(raw).expanduser()
    if p.suffix == ".toml" or os.sep in raw:
        if p.is_file():
            return p.resolve()
        raise ProfileError(f"{raw}: profile file not found; give an existing .toml path or a name")
    for d in search_dirs():
        cand = d / f"{raw}.toml"
        if cand.is_file():
            return cand.resolve()
    # lazy: the estop path stays standard-library only
    from console.core.suggest import suggestion

    known = sorted(known_profiles())
    hint = suggestion(raw, known)
    raise ProfileError(
        f"profile {raw!r} not found{hint}; known profiles: {', '.join(known) or 'none'} "
        f"(searched {', '.join(str(d) for d in search_dirs())})"
    )


def known_profiles() -> dict[str, Path]:
    """Every profile found by name: name -> its file (the first of a name wins)."""
    found: dict[str, Path] = {}
    for d in search_dirs():
        try:
            files = sorted(d.glob("*.toml")) if d.is_dir() else []
        except OSError:
            files = []
        for q in files:
            if q.is_file():
                found.setdefault(q.stem, q.resolve())
    return found
