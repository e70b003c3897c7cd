"""A help entry whose key is several words (``page down / page up: ...``) is an entry of
its own, not joined to the line above (Vibration's help read ``x: cancel what runs page
down / page up: ...``)."""

from __future__ import annotations

from console.tui.help import paragraphs
from console.tui.panes.vibration_words import HELP_KEYS


def test_a_key_of_several_words_starts_its_own_entry():
    got = paragraphs(HELP_KEYS)
    assert any(p.startswith("page down / page up: scroll") for p in got), got
    assert any(p == "b: build the lookup tables   x: cancel what runs" for p in got), got
    # a hard-wrapped sentence still joins back
    assert paragraphs("m: measure the map\nwith the vibrometer") == [
        "m: measure the map with the vibrometer"
    ]
