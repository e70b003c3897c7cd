"""A number stays on the line of its unit and its label, wherever the console's text is
wrapped (``console.tui.glue``): Textual's wrapping of a widget's text, the console's own
(help, the camera view's message, the camera's live numbers), and on a screen: the
Camera status line at 80 x 24 and 120 x 40 (an operator read ``... 0`` / ``s``,
``(1`` / ``s)``, ``fps`` / ``54.08``)."""

from __future__ import annotations

import asyncio

import pytest
from textual.content import Content

import console.tui  # noqa: F401 - installs the glue into Textual's wrapping
from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.camera_live import hang
from console.tui.camera_picture import wrap_markup
from console.tui.glue import groups, stays_together, wrap

from .conftest import wait_for
from .test_camera_layout import SIZES, _first_frame, screen_lines

SAID = (
    "loading the vision (gesture classifier) ... 0 s",
    "p  play the setting (1 s) on the plate",
    "twin camera 7 fps, vision 7 fps, loop fps 54.08 now",
    "leave-one-out 2.72 mm; outliers none; 375,240 mm: e measures it",
)


def split_apart(lines: list[str]) -> list[tuple[str, str]]:
    """The line ends where a number is parted from its unit or label."""
    return [
        (a, b)
        for a, b in zip(lines, lines[1:], strict=False)
        if a.split() and b.split() and stays_together(a.split()[-1], b.split()[0])
    ]


def test_what_stays_together():
    for left, right in [("0", "s"), ("(1", "s)"), ("2.72", "mm);"), ("fps", "54.08"), ("-15", "V")]:
        assert stays_together(left, right), (left, right)
    for left, right in [("the", "s"), ("0", "of"), ("fps,", "vision"), ("1", "2"), ("s", "0")]:
        assert not stays_together(left, right), (left, right)
    assert groups("at 375,240 mm: e  x") == ["at", "375,240 mm:", "e", "", "x"]


@pytest.mark.parametrize("text", SAID)
def test_no_wrapper_parts_a_number_from_its_unit(text):
    for width in range(max(map(len, groups(text))) + 2, len(text) + 1):
        for how, lines in (
            ("textual", [str(ln) for ln in Content(text).wrap(width)]),
            ("wrap", wrap(text, width, break_on_hyphens=False)),
            ("view", wrap_markup(text, width).split("\n")),
            ("hang", [ln.strip() for ln in hang([text], width)]),
        ):
            assert split_apart(lines) == [], (how, width, lines)
            # nothing lost, nothing added
            assert " ".join(" ".join(lines).split()) == " ".join(text.split()), (how, lines)


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_camera_status_line_keeps_a_number_with_its_unit(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            pane = app.pane("camera")
            status = app.query_one("#camera-status")
            pane.say("e: measuring touching skin ...")
            await wait_for(pilot, lambda: status.content_region.width > 8, 10, "laid out")
            width = status.content_region.width
            # a line whose first row would end with the number, its unit on the next
            head = "e: set exposure after "
            text = head + "x" * (width - len(head) - 2) + " 0 s, gain 1 (touching skin)"
            pane.say(text)
            region = lambda: status.content_region  # noqa: E731
            await wait_for(pilot, lambda: "touching skin)" in "".join(screen_lines(app)), 10, "it")
            r = region()
            rows = [row[r.x : r.right].strip() for row in screen_lines(app)[r.y : r.bottom]]
            assert any(row.startswith("0 s, gain") for row in rows), rows
            assert split_apart(rows) == [], rows

    asyncio.run(scenario())
