"""README's screen table names every key each screen binds, read from the screens'
bindings (the Camera row and its Gestures panel: ``test_readme_camera_keys``): a key a
screen answers to that README does not name is a key an operator cannot find."""

from __future__ import annotations

import importlib
import re

import pytest

from .test_readme_camera_keys import SHOWN, _keys_named, _row

#: ``=`` is ``+`` without shift: a row naming ``+`` names it
SHOWN_TOO = {
    "up": "↑",
    "down": "↓",
    "equals_sign": "+",
    "colon": ":",
    "delete": "Delete",
    "pagedown": "PageDown",
    "pageup": "PageUp",
}

#: screen -> the classes whose bindings it answers to
SCREENS = {
    "Devices": ["console.tui.panes.devices:DevicesPane"],
    "Vibration": [
        "console.tui.panes.vibration:VibrationPane",
        "console.tui.panes.vibration_grid:*",
    ],
    "Relays": ["console.tui.panes.relays:RelaysPane"],
    "Electrostatic": ["plugins.electrostatic.panel:ElectrostaticPane"],
    "Scenes": ["plugins.demos.panel:ScenesPane", "plugins.demos.tables:*"],
    "Latency": ["console.tui.panes.latency:LatencyPane"],
    "Signals": ["console.tui.panes.signals:SignalsPane"],
    "Scope": ["console.tui.panes.scope:ScopePane"],
    "Studies": ["plugins.studies.panel:StudiesPane"],
}

#: keys a row names in words
WORDS = {
    ("↑", "↓", "←", "→"): ("arrows",),
    ("Esc",): ("Esc", "Escape"),
    ("enter",): ("Enter",),
    ("space",): ("space",),
    ("tab",): ("Tab",),
}


def _bindings(spec: str) -> list:
    module, _, name = spec.partition(":")
    mod = importlib.import_module(module)
    if name != "*":
        return list(getattr(mod, name).BINDINGS)
    return [b for obj in vars(mod).values() if isinstance(obj, type) and obj.__module__ == module
            for b in obj.__dict__.get("BINDINGS", [])]  # fmt: skip


def _keys(bindings) -> set[str]:
    out = set()
    for b in bindings:
        for key in (b[0] if isinstance(b, tuple) else b.key).split(","):
            if key != "question_mark":  # ``?``: every screen's help, said once above the table
                out.add(SHOWN_TOO.get(key, SHOWN.get(key, key)))
    return out


def _named(row: str) -> set[str]:
    named = _keys_named(row) | ({":"} if "`:`" in row else set())
    for a, b in re.findall(r"`(\d)`\s*(?:-|\.\.)\s*`(\d)`", row):  # `1`-`8`, `1`..`3`
        named.update(str(d) for d in range(int(a), int(b) + 1))
    for keys, words in WORDS.items():
        if any(re.search(rf"\b{w}\b", row) for w in words):
            named.update(keys)
    return named | {k.lower() for k in named if k in ("Enter", "Tab")}


@pytest.mark.parametrize("screen", sorted(SCREENS))
def test_readme_row_names_every_key_the_screen_binds(screen):
    row = _row(screen)
    keys = _keys([b for spec in SCREENS[screen] for b in _bindings(spec)])
    missing = keys - _named(row)
    assert not missing, f"README's {screen} row names no {sorted(missing)}"
