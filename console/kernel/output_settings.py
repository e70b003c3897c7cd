"""The profile settings a table's outputs depend on, and how two clients' differ.

One kernel serves every client of a table; a client joins it only when the kernel runs
its settings. Every section counts but those that never reach the outputs
(``NOT_OUTPUT_SECTIONS``: camera, vision, TUIO, projector, console, demos' and studies'
own settings): switching one in the console (``u`` saves TUIO to the profile's
overrides) must not lock a shell's ``haptable play`` out, and a section nobody listed
counts, so the mistake possible is a refusal, never outputs shared across other limits.
"""

from __future__ import annotations

import hashlib
import json
from typing import Any

from console.kernel.wire import jsonable

#: the sections that never reach the outputs: what the camera, the vision, the
#: classifier, TUIO, the projector, the demos' and studies' own settings, the console and
#: the recordings hold. Every other section counts (a driver plugin's new section
#: included): a section forgotten here refuses a client it could have served, never
#: lets one join outputs opened with other limits or wiring.
NOT_OUTPUT_SECTIONS = frozenset(
    {
        "profile",
        "camera",
        "twin_camera",
        "vision",
        "svm",
        "gestures",
        "tuio",
        "projector",
        "console",
        "scenes",
        "demos",
        "flow",
        "hand_flow",
        "knob",
        "runtime",
        "recording",
        "replay",
        "selftest",
        "perception",
        "studies",
    }
)

#: keys named in a refusal before "and N more"
SHOWN_KEYS = 3


def _flat(prefix: str, value: Any, out: dict[str, Any]) -> None:
    if isinstance(value, dict):
        for k, v in value.items():
            _flat(f"{prefix}.{k}" if prefix else str(k), v, out)
    else:
        out[prefix] = value


def output_settings(profile: Any) -> dict[str, Any]:
    """The profile's output settings, flat ``{"limits.piezo_max_v": 250.0, ...}``, as
    JSON has them (a kernel sends them in its hello)."""
    out: dict[str, Any] = {}
    data = jsonable(profile.data)
    for section, value in data.items():
        if section not in NOT_OUTPUT_SECTIONS:
            _flat(section, value, out)
    return out


def settings_key(profile: Any) -> str:
    """What a client compares to know a kernel runs its profile's output settings."""
    raw = json.dumps(output_settings(profile), sort_keys=True)
    return hashlib.sha1(raw.encode()).hexdigest()[:16]


def differing(theirs: dict[str, Any], ours: dict[str, Any]) -> list[str]:
    """The keys whose values differ (or that one side lacks), sorted."""
    return sorted(k for k in set(theirs) | set(ours) if theirs.get(k) != ours.get(k))


def _value(v: Any) -> str:
    return "(unset)" if v is None else json.dumps(v)


def refusal(table: str, holders: list[str], theirs: dict[str, Any] | None, ours: Any) -> str:
    """One line: the table's outputs are open by ``holders`` with other output settings;
    which keys differ (their value vs this profile's, when the kernel said them) and the
    fix."""
    who = ", ".join(holders or ["another process"])
    if not theirs:
        return (
            f"table {table}: its outputs are open with other output settings by {who}; "
            "quit it first, or give this profile the same settings"
        )
    mine = output_settings(ours)
    keys = differing(theirs, mine)
    said = [f"{k} {_value(theirs.get(k))} there, {_value(mine.get(k))} here" for k in keys]
    more = f" and {len(said) - SHOWN_KEYS} more" if len(said) > SHOWN_KEYS else ""
    return (
        f"table {table}: its outputs are open by {who} with other output settings "
        f"({'; '.join(said[:SHOWN_KEYS])}{more}); quit it first, or set the same "
        f"{'value' if len(keys) == 1 else 'values'} in this profile"
    )
