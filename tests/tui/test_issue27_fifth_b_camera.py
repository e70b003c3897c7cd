"""Issue 27 (fifth, b): the Camera screen's exposure assistant on the twin at 80 x 24:
when the twin's hand came and went in the frames measured, ``e`` says so (never "no
hand" beside a panel showing one) and names ``P``, the key that holds a flat hand still
on the twin's glass; with it held, ``e`` measures it; ``P`` again: its gestures in turn."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.runtime import exposure_assist
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera_layout import _first_frame


def test_e_names_the_key_that_holds_a_hand_on_the_twin(plugins, monkeypatch):
    real = exposure_assist.service_measure
    calls: list[int] = []  # the first e: the hand missing from the frames measured

    def measure(svc, cancel, **kw):
        calls.append(1)
        return (lambda: None) if len(calls) == 1 else real(svc, cancel, **kw)

    monkeypatch.setattr(exposure_assist, "service_measure", measure)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="camera")
        async with app.run_test(size=(80, 24)) as pilot:
            await _first_frame(app, pilot)

            def status() -> str:
                return words_on(app, "#camera-status")

            await pilot.press("e")
            await wait_for(pilot, lambda: "frames measured" in status(), 30, "e")
            assert "came and went" in status() and "P holds a flat hand" in status()
            assert "no hand touching" not in status()
            await pilot.press("P")
            await wait_for(pilot, lambda: "held still" in status(), 10, "P")
            assert "e measures it" in status()
            # what P again does, in the README's words (it said "P lets it go")
            assert "P again: its gestures in turn" in status(), status()
            await pilot.press("e")
            await wait_for(pilot, lambda: "of 255" in status(), 60, "e measured")
            await pilot.press("P")
            await wait_for(pilot, lambda: "gestures in turn" in status(), 10, "P again")

    asyncio.run(scenario())
