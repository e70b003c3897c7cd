"""Latency (F7): for the first second after ``m`` the camera's line says plainly that
it is counting, with no "?" for what is not known yet (a new operator read
``camera ?: fps counting ..., ? frames delivered``)."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp
from console.tui.panes.latency import camera_line

from .conftest import wait_for


def test_the_camera_line_before_its_first_numbers_says_it_counts():
    line = camera_line({}, None)
    assert "?" not in line and "counting" in line, line
    line = camera_line({"driver": "twin", "frames": 12}, None)
    assert "twin" in line and "12 frames" in line and "?" not in line, line


def test_the_first_second_after_m_says_it_is_counting(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="latency")
        async with app.run_test(size=(80, 24)) as pilot:
            head = app.query_one("#lat-head")
            await wait_for(pilot, lambda: "m measures" in str(head.render()), 20, "idle hint")
            seen: list[str] = []
            pane = app.pane("latency")
            real = pane._say

            def spy(wid, text, *a, **kw):
                if wid == "lat-head":
                    seen.append(str(text))
                return real(wid, text, *a, **kw)

            pane._say = spy
            await pilot.press("m")
            await wait_for(pilot, lambda: any(" fps delivered" in t for t in seen), 30, "fps")
            counting = [t for t in seen if "camera" in t and "fps delivered" not in t]
            for text in counting:
                line = text.split("\n")[-1]
                assert "?" not in line, line
            assert any("counting" in t for t in counting), seen

    asyncio.run(scenario())
