"""The Camera side panel's lines are wrapped for the width they are shown at: the
view's title grew a column past the picture when its grey levels reached three digits
(``grey 10 to 110``), the view's column (``width: auto``) with it, the side panel lost
that column while its lines, wrapped for the width before, were kept for half a second:
Textual wrapped the too-long line again, leaving one word alone on a row ('touching
skin at 219 of 255 in' / 'the' / '  image, 185 ...'; a clean clone's README command at
80 x 24). The title is now cut to the picture's width, and the live lines are wrapped
again at once when their width changes (a resized terminal)."""

from __future__ import annotations

import asyncio
import time

import pytest
from rich.text import Text

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for


def _too_long(parts) -> list[tuple[int, str]]:
    """Each line of ``parts`` wider than the part shows it (wrapped again by Textual)."""
    out = []
    for part in parts:
        width = part.content_size.width
        for line in str(part.content).splitlines():
            if width and Text.from_markup(line.rstrip()).cell_len > width:
                out.append((width, line))
    return out


@pytest.mark.parametrize("size", [(80, 24), (120, 40)], ids=["80x24", "120x40"])
def test_side_panel_lines_fit_the_width_they_are_shown_at(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            parts = [app.query_one(f"#camera-{n}") for n in ("info", "measures", "detail")]
            await wait_for(pilot, lambda: "touching" in str(parts[1].content), 30, "skin")
            # the twin's flat hand brightens the frame: the levels reach three digits
            await pilot.press("P")
            main, view = app.query_one("#camera-main"), app.query_one("#camera-view")
            too_long, widths = [], set()
            t_end = time.monotonic() + 3.0
            while time.monotonic() < t_end:
                await pilot.pause(0.05)
                too_long += _too_long(parts)
                widths.add((main.size.width, view.size.width))
            assert not too_long, too_long[:3]
            # the view's column is its picture's width, whatever its title says
            assert all(m == v for m, v in widths), widths
            # a resized terminal (the picture wider, the panel narrower at 80 x 24): the
            # lines wrapped again for the panel's new width at once
            await pilot.resize_terminal(size[0] + 7, size[1])
            t_end = time.monotonic() + 1.0
            while time.monotonic() < t_end:
                await pilot.pause(0.05)
                too_long += _too_long(parts)
            assert not too_long, too_long[:3]

    asyncio.run(scenario())
