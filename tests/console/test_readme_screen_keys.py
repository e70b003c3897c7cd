"""README's screen table names every key each screen binds, read from the screens'
bindings and the widgets on them that answer keys (the relays' switches, the library
list, the ``:`` line; the Camera row and its Gestures panel: ``test_readme_camera_keys``):
a key a screen answers to that README does not name is a key an operator cannot find.
Each screen's help (``?``) names them too, and README names no key as a screen's that
nothing on it (nor the console: ``?``, ``ctrl+e`` ...) binds."""

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
        "console.tui.command_line:CommandLine",
    ],
    "Relays": ["console.tui.panes.relays:RelaysPane", "textual.widgets:Switch"],
    "Electrostatic": ["plugins.electrostatic.panel:ElectrostaticPane"],
    "Scenes": ["plugins.demos.panel:ScenesPane", "plugins.demos.tables:*"],
    "Latency": ["console.tui.panes.latency:LatencyPane"],
    "Signals": ["console.tui.panes.signals:SignalsPane", "console.tui.list_keys:KeyedList"],
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
    ("Delete",): ("Delete",),
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


#: a screen's help: the class with its ``HELP_TEXT`` (the first of ``SCREENS``)
HELPS = {screen: specs[0] for screen, specs in SCREENS.items()} | {
    "Camera": "console.tui.panes.camera:CameraPane",
    "Gestures": "plugins.gestures.panel:GesturesPanel",  # Camera's g
}
#: keys a help names in words
HELP_WORDS = {
    **{k: (k.lower(),) for k in ("Enter", "Tab", "Delete", "space", "home", "end")},
    "Esc": ("esc", "escape"),
    "PageDown": ("page down",),
    "PageUp": ("page up",),
    "←": ("arrows", "left"),
    "→": ("arrows", "right"),
    "↑": ("arrows",),
    "↓": ("arrows",),
}
#: backquoted words of a row that are shown values, not keys: a cut, a grid mark, volts,
#: a signal expression's signs and numbers, an adaptive plot's marks
NOT_KEYS = {
    "Devices": {"…"},
    "Vibration": {"·"},
    "Relays": {"V"},
    "Signals": {"*", "3", "4", "V", "s"},
    "Studies": {"+", "x", "◆"},
}


def _help_named(text: str) -> set[str]:
    """The keys a help text names: its words and signs, ranges (``1-8``, ``1..7``, ``up
    to 9``) and keys said in words (``page down``, ``arrows``, ``escape``)."""
    named = {w.strip(".,;:()") for w in re.split(r"[\s/]+", text) if w} | set(text)
    named |= {w.strip(".,;:()").lower() for w in re.split(r"[\s/]+", text) if w}
    for a, b in re.findall(r"\b(\d)\s*(?:-|\.\.)\s*(\d)\b", text):
        named.update(str(d) for d in range(int(a), int(b) + 1))
    low = text.lower()
    for key, words in HELP_WORDS.items():
        if any(re.search(rf"\b{re.escape(w)}\b", low) for w in words):
            named.add(key)
    return named


def _screen_keys(screen: str) -> set[str]:
    if screen in ("Camera", "Gestures"):
        from .test_readme_camera_keys import _bindings_keys

        return _bindings_keys(_bindings(HELPS[screen]))
    return _keys([b for spec in SCREENS[screen] for b in _bindings(spec)])


@pytest.mark.parametrize("screen", sorted(HELPS))
def test_the_screen_s_help_names_every_key_it_binds(screen):
    module, _, name = HELPS[screen].partition(":")
    help_text = getattr(importlib.import_module(module), name).HELP_TEXT
    missing = _screen_keys(screen) - _help_named(help_text)
    assert not missing, f"{screen}'s help (?) names no {sorted(missing)}"


@pytest.mark.parametrize("screen", sorted(SCREENS))
def test_readme_row_names_no_key_the_screen_does_not_bind(screen):
    from console.tui.app import HapTableApp

    console = _keys(HapTableApp.BINDINGS) | {"?", "ctrl+p", "ctrl+q"}
    keylike = re.compile(r"^(?:\S|ctrl\+\w|Esc|Escape|Enter|Tab|space|PageUp|PageDown|Delete)$")
    spans = re.findall(r"`([^`]+)`", _row(screen))
    said = {w.strip(":,") for span in spans for w in re.split(r"[\s/]+", span) if w.strip(":,")}
    keys = {k for k in said if keylike.match(k)} - NOT_KEYS.get(screen, set())
    bound = _screen_keys(screen) | {k.lower() for k in _screen_keys(screen)} | console
    words = {"Esc": "escape", "Escape": "escape", "Enter": "enter", "Tab": "tab"}
    unbound = {k for k in keys if k not in bound and words.get(k, k) not in bound}
    assert not unbound, f"README's {screen} row names {sorted(unbound)}: nothing binds them"
