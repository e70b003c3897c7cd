"""Camera (F2): a status line never takes the place of what the vision measures of
touching skin (``touching skin at N of 255 ...``, ``touches: ...``). After
``b``, ``W``, ``o`` or ``e`` the status took their rows and left ends of their wrapped lines
in view (``margin``, ``both in grey over the background``: new operator's report, finding
2). Those lines are now pinned with the live numbers above the status; the status (a
question, a field's reply, a result) keeps its words and rows whole, and the live block
gives way to it only by whole lines from its end, never leaving a fragment."""

from __future__ import annotations

import asyncio

import pytest

from console.tui.camera_live import HANG

from .conftest import wait_for
from .test_camera_layout import _app, _first_frame, text_in


def _side(app) -> str:
    return text_in(app, app.query_one("#camera-side"))


def _info_rows_cut_whole(app) -> None:
    """The live block shows whole lines only: no continuation without its line, none
    of its lines without its continuation."""
    for part in ("#camera-info", "#camera-measures"):
        block = app.query_one(part)
        lines = str(block.content).split("\n")
        shown = block.region.height if block.display else 0
        assert shown == 0 or shown >= len(lines) or not lines[shown].startswith(HANG), (
            f"{part} cut inside a line at row {shown}: {lines}"
        )


#: each key and what its reply says (``e``: its result, once no step says ``x stops``)
REPLIES = [
    ("b", "background"),
    ("W", "again within 3 s"),
    ("o", "recording's path"),
    ("e", "of 255"),
]
#: the ends of the skin lines' wrapped rows, read alone as lines of their own: each
#: with the start of its line (the skin's, the touches')
FRAGMENTS = {
    "over the empty table": "touching skin at",
    "of contact_level": "touches:",
    "enough to be seen": "touches:",
    "may be missed": "touches:",
}


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
@pytest.mark.parametrize(("key", "reply"), REPLIES, ids=[k for k, _ in REPLIES])
def test_a_status_line_leaves_what_the_vision_measures_whole(plugins, size, key, reply):
    async def scenario():
        app = _app(plugins)
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            await pilot.press("P")  # the twin's flat hand held still on the glass
            await wait_for(pilot, lambda: "touches:" in _side(app), 30, "skin measured")
            await pilot.press(key)
            status = app.query_one("#camera-status")

            def replied() -> bool:
                said = text_in(app, status)
                return reply in said and "x stops" not in said

            await wait_for(pilot, replied, 60, "the reply")
            await pilot.pause(1.0)  # a few redraws of the live numbers
            side = _side(app)
            # the reply whole, every word of it (none given way to the live numbers)
            assert text_in(app, status) == " ".join(str(status.content).split()), side
            assert "…" not in text_in(app, status), side
            # no end of a skin line without its start, nor the skin lines without the
            # first of them (``W``, ``e``: only their last rows were left in view)
            for end, start in FRAGMENTS.items():
                assert end not in side or start in side, side
            if "touches:" in side:
                assert "touching skin at" in side, side
            _info_rows_cut_whole(app)
            assert "camera lost" in side and "hand at" in side, side  # the live numbers
            if size == (120, 40):  # room for all of it
                assert "touching skin at" in side and "contact_level 180" in side, side
                assert "over the empty table" in side, side

    asyncio.run(scenario())
