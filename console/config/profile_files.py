"""The files the console keeps per profile (touch calibration, trained gesture model,
projector calibration ...): under the user's state directory, never beside the profile.

``profile_file(profile, "vision.calibration", "touch_calibration.json")`` is the one path
both the reader and the writer use:

- the profile names the file (``[vision] calibration = "cal.json"``): that path, relative
  to the profile's folder, read and written as given;
- else ``console.files.paths.profile_state_dir(<profile name>, name)``.

A file an earlier version kept beside the profile by default (``legacy``, default
``name``) is never silently ignored: with no file in the state directory yet, it is copied
there (the original stays: the profile's folder may be read-only) and one log line says
where it now belongs; when both exist, one log line says the old one is not used.
"""

from __future__ import annotations

import logging
import shutil
import threading
from pathlib import Path
from typing import Any

from console.core.errors import UserError
from console.files import paths

log = logging.getLogger("haptable.files")

_told: set[tuple[str, str]] = set()  # (old, new) pairs already logged in this process
_told_lock = threading.Lock()


def profile_file(profile: Any, key: str, name: str, legacy: str | None = None) -> Path:
    """Where the profile's ``key`` file is read and written: the profile's own path when
    it names one, else ``name`` in the profile's state directory (an old default file
    ``legacy`` beside the profile copied there first)."""
    raw = str(profile.get(key) or "")
    if raw:
        return profile.resolve(raw)
    home = paths.profile_state_dir(profile.name, name)
    old = Path(profile.path).parent / (legacy or name)
    if old.is_file() and old.resolve() != home.resolve():
        _adopt(old, home, key)
    return home


def _adopt(old: Path, home: Path, key: str) -> None:
    section, _, item = key.partition(".")
    where = f"the default of [{section}] {item}"
    if home.exists():
        _tell(old, home, f"%s: not used, %s is ({where}); delete the old one")
        return
    try:
        home.parent.mkdir(parents=True, exist_ok=True)
        tmp = home.with_name(home.name + ".part")
        shutil.copy2(old, tmp)
        tmp.replace(home)
    except OSError as exc:
        raise _unwritable(home, exc) from None
    _tell(old, home, f"%s: found beside the profile; it now belongs in %s ({where}): copied there")


def _tell(old: Path, home: Path, msg: str) -> None:
    with _told_lock:
        if (str(old), str(home)) in _told:
            return
        _told.add((str(old), str(home)))
    log.warning(msg, old, home)


def _unwritable(home: Path, exc: OSError) -> UserError:
    return UserError(
        f"{home}: cannot write ({exc.strerror or exc}); make the state directory writable "
        "or set $HAPTABLE_STATE_DIR"
    )
