"""Issue 27: README's Camera row (F2) names every key of the Camera screen and of its
Gestures panel (``g``), read from their bindings, and the time window in which a second
``s`` starts the synthesis whose size and time the panel said."""

from __future__ import annotations

import re
from pathlib import Path

README = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")

#: a binding's key as README writes it
SHOWN = {
    "right_square_bracket": "]",
    "left_square_bracket": "[",
    "plus": "+",
    "minus": "-",
    "escape": "Esc",
    "right": "→",
    "left": "←",
    "pageup": "PageUp",
    "pagedown": "PageDown",
}


def _row(screen: str) -> str:
    rows = [ln for ln in README.splitlines() if re.match(rf"\| F\d+ \| {screen} \|", ln)]
    assert len(rows) == 1, f"README: one screen-table row for {screen}"
    return rows[0]


def _keys_named(text: str) -> set[str]:
    """The keys in ``text``'s backquoted spans (`t/T c/C h/H`, `S: save`, `Esc`)."""
    out = set()
    for span in re.findall(r"`([^`]+)`", text):
        out.update(w.strip(":,") for w in re.split(r"[\s/]+", span) if w)
    return out


def _bindings_keys(bindings) -> set[str]:
    keys = {b.key for b in bindings if b.key != "question_mark"}  # ``?``: every screen's help
    return {SHOWN.get(k, k) for k in keys}


def test_readme_camera_row_names_every_camera_and_gestures_panel_key():
    from console.tui.camera_keys import BINDINGS as CAMERA
    from plugins.gestures.panel import CONFIRM_S, GesturesPanel

    row = _row("Camera")
    camera, _, gestures = row.partition("the Gestures panel (`g`:")
    assert gestures, "README's Camera row: the Gestures panel (`g`: ...)"
    missing = _bindings_keys(CAMERA) - _keys_named(camera) - {"g"}
    assert not missing, f"README's Camera row names no {sorted(missing)}"
    missing = _bindings_keys(GesturesPanel.BINDINGS) - _keys_named(gestures)
    assert not missing, f"README's Gestures panel names no {sorted(missing)}"
    # the panel's s: its estimate, then s again within the window it states
    assert f"`s again within {CONFIRM_S:.0f} s to start: ...`" in gestures
    assert f"`s` again within those {CONFIRM_S:.0f} s" in gestures
