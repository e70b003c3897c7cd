"""Numbers on screen say their units and meaning (issue 27): the Latency screen's audio
block also in time ("block 64 samples = 1.33 ms at 48 kHz"), the Camera view's grey range
unambiguous with negative ends ("grey -15 to 17", never "-15-17"), the twin camera's
exposure and gain as the multipliers they are ("exposure x1"), a real driver's as its
raw value or "auto", and the knob demo's "no item" for its -1; at 80 x 24 and 120 x 40."""

from __future__ import annotations

import asyncio
import re

import pytest

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for
from .test_camera_layout import _first_frame, screen_lines

SIZES = [(80, 24), (120, 40)]


@pytest.mark.parametrize("size", SIZES)
def test_the_latency_screen_says_the_block_in_time(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=size) as pilot:

            def audio() -> str:
                found = app.query("#lat-audio")
                return " ".join(str(found.first().render()).split()) if found else ""

            await wait_for(pilot, lambda: "block" in audio(), 30, "the audio line")
            line = audio()
            m = re.search(r"block (\d+) samples = ([\d.]+) ms at ([\d.]+) kHz", line)
            assert m, line
            n, ms, khz = int(m[1]), float(m[2]), float(m[3])
            assert ms == pytest.approx(n / (khz * 1e3) * 1e3, abs=0.01), line
            assert " Hz" not in line.replace("kHz", ""), line  # no 48000 Hz beside it

    asyncio.run(scenario())


#: a Camera view's title's levels, as ``console.tui.units.view_levels`` says them
VIEW_TITLE = r"grey \d+ to \d+|[-+]\d+\.\.[-+]\d+ grey|white over the body"


@pytest.mark.parametrize("size", SIZES)
def test_the_camera_grey_range_and_controls_read_unambiguously(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=size) as pilot:
            await _first_frame(app, pilot)
            for _view in range(4):  # camera, diff (negative levels), high-pass, body
                # the camera's levels "8 to 81", a signed range "-1..+31" (a view's own
                # terms: ``test_camera_view_title_terms``), never "-1-31"
                await wait_for(
                    pilot,
                    lambda: any(re.search(VIEW_TITLE, ln) for ln in screen_lines(app)),
                    20,
                    "the view's title",
                )
                assert not any(re.search(r"grey -?\d+-", ln) for ln in screen_lines(app))
                await pilot.press("v")
                await pilot.pause(0.3)
            settings = str(app.query_one("#camera-settings").render())
            assert re.search(r"exposure x[\d.]+", settings), settings
            assert re.search(r"gain x[\d.]+", settings), settings

    asyncio.run(scenario())


def test_a_real_cameras_controls_say_raw_or_auto():
    from console.tui.units import control_words

    assert control_words("exposure", -1.0, "opencv") == "exposure auto"
    assert control_words("gain", 64.0, "opencv") == "gain 64 (raw driver value)"
    assert control_words("exposure", 1.5, "twin") == "exposure x1.5"


def test_the_knob_demo_says_no_item_for_its_minus_one():
    from plugins.demos.status import status_lines

    snap = {
        "demo": "knob",
        "camera": {},
        "latency": {},
        "knob": {"condition": "C1", "item": -1, "angle_deg": 0.0, "crossings": 0},
    }
    knob = next(ln for ln in status_lines(snap) if ln.startswith("knob"))
    assert "no item" in knob and "item -1" not in knob, knob
    snap["knob"]["item"] = 3
    knob = next(ln for ln in status_lines(snap) if ln.startswith("knob"))
    assert "item 3" in knob, knob
