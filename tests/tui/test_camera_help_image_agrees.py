"""Camera (F2): its help (`?`) and the README say the same ways to choose the IR view's
drawing: the profile's `[console] image` and `haptable console --image` (the switch the
README names; a new operator's try found the help without it), each with every mode the
switch takes (``console.config.core_sections.IMAGE_MODES``)."""

from __future__ import annotations

from pathlib import Path

from console.config.core_sections import IMAGE_MODES
from console.tui.camera_keys import HELP_TEXT

README = Path(__file__).resolve().parents[2] / "README.md"


def _readme_image_paragraph() -> str:
    text = README.read_text(encoding="utf-8")
    start = text.index("`[console] image = ")
    return " ".join(text[start - 200 : start + 400].split())


def test_the_camera_help_and_the_readme_name_the_same_ways_and_modes():
    help_text = " ".join(HELP_TEXT.split())
    readme = _readme_image_paragraph()
    for said in ("[console] image", "haptable console --image"):
        assert said in help_text, (said, help_text)
        assert said in readme, (said, readme)
    for mode in IMAGE_MODES:
        assert mode in help_text, (mode, help_text)
        assert mode in readme, (mode, readme)
