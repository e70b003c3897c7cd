"""The self-test's last outcome per profile, as `haptable doctor` (its quick part) and
the console's Devices screen (``s``: the full one) ran it, kept between runs: the
Devices screen's self-test row says what ran, where and when, never "not run" after a
doctor's quick part said ok. One JSON file in the profile's state folder: ``{"quick":
{...}, "full": {...}}``, each ``{"state", "line", "by", "time"}``."""

from __future__ import annotations

import json
import logging
import time

from console.files.atomic import write_text_atomic
from console.files.paths import profile_state_dir

log = logging.getLogger(__name__)

#: the file, in ``profile_state_dir(<profile>)``
FILE = "selftest_last.json"
#: the parts a record keeps (``stopped``: the console's last full run, stopped before its
#: end, e.g. by the e-stop; said first on the row until a full run ends)
KINDS = ("quick", "full", "stopped")


def read_last(profile_name: str) -> dict[str, dict[str, str]]:
    """The kept outcomes (``{}``: none, or a file that cannot be read as ours)."""
    path = profile_state_dir(profile_name, FILE)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    if not isinstance(data, dict):
        return {}
    return {
        k: {f: str(v.get(f, "")) for f in ("state", "line", "by", "time")}
        for k, v in data.items()
        if k in KINDS and isinstance(v, dict)
    }


def note_last(profile_name: str, kind: str, state: str, line: str, by: str) -> None:
    """Keep ``kind``'s outcome (``state``: ok, error, skipped; ``line``: what it said;
    ``by``: which command ran it). A file that cannot be written is logged, not raised:
    the test's own report is what counts."""
    if kind not in KINDS:
        raise ValueError(f"self-test kind {kind!r}: one of {', '.join(KINDS)}")
    data = read_last(profile_name)
    data[kind] = {
        "state": state,
        "line": " ".join(str(line).split())[:300],
        "by": by,
        "time": time.strftime("%Y-%m-%d %H:%M"),
    }
    _write(profile_name, data)


def forget_last(profile_name: str, kind: str) -> None:
    """``kind``'s record gone (a stopped run once a full one has ended)."""
    data = read_last(profile_name)
    if data.pop(kind, None) is not None:
        _write(profile_name, data)


def _write(profile_name: str, data: dict) -> None:
    path = profile_state_dir(profile_name, FILE)
    try:
        write_text_atomic(path, json.dumps(data))
    except OSError as exc:
        log.warning("the self-test's outcome not kept in %s: %s", path, exc)
