"""Issue 27, finding 15: the long-work line (the Gestures panel's training, every
``LongWork``) says the time left at every step once the pace tells it, a step that
takes longer than expected too (it said none then), and its bar only moves forward."""

from __future__ import annotations

import asyncio
import threading

import pytest
from textual.app import App

from console.tui.long_work import LongWork

from .conftest import wait_for


class Host(App):
    def compose(self):
        yield LongWork(id="w")


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_every_step_says_the_time_left_and_the_bar_never_goes_back(size):
    go = {k: threading.Event() for k in ("overrun", "back", "end")}

    def job(progress, cancelled):
        progress(0.3, "fold 1/2: training")
        threading.Event().wait(1.2)  # the pace: over a second for 30 %
        progress(0.9, "training on every sample")
        go["overrun"].wait(20)  # the fit expected in 0.2 s takes longer
        progress(0.5, "a step reporting less")  # a later part counting from lower
        go["back"].wait(20)
        go["end"].wait(20)
        return 1

    async def scenario():
        app = Host()
        async with app.run_test(size=size) as pilot:
            work = app.query_one(LongWork)
            assert work.start("training", job)
            await wait_for(pilot, lambda: "every sample" in work.text, 20, "the final fit")
            work.expect(0.97, 0.2)  # as the Gestures panel paces the final fit
            await pilot.pause(1.0)  # well over the step's 0.2 s
            work._tick()
            assert "every sample" in work.text and " left" in work.text, work.text
            furthest = work.progress
            assert furthest is not None and furthest > 0.9
            go["overrun"].set()
            await wait_for(pilot, lambda: "reporting less" in work.text, 20, "a lower report")
            assert work.progress >= furthest, (work.progress, furthest)  # never back
            assert " left" in work.text, work.text
            go["back"].set()
            go["end"].set()
            await wait_for(pilot, lambda: work.outcome == "done", 20, "done")

    asyncio.run(scenario())
