"""Issue 27: the Gestures panel's training said "7 s, 9 s, 10 s left" at 28 to 38 %: the
time left of every ``LongWork`` rose with the clock between reports. It counts down
between reports and rises at a report by noise only; once it ran out (the work is later
than said) the pace so far stands."""

from __future__ import annotations

import asyncio
import re
import threading

import pytest
from textual.app import App

from console.tui.long_work import LongWork
from console.tui.time_left import Steady

from .conftest import wait_for


class Host(App):
    def compose(self):
        yield LongWork(id="w")


def _left_s(text: str) -> int:
    if "less than 1 s left" in text:
        return 0
    m = re.search(r"about (\d+) s left", text)
    assert m, text
    return int(m.group(1))


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_time_left_never_rises_between_reports(size):
    go = threading.Event()

    def job(progress, cancelled):
        threading.Event().wait(3.0)
        progress(0.3, "fold 1/2: training")  # 3 s for 30 %: about 7 s left
        go.wait(20)
        return 1

    async def scenario():
        app = Host()
        async with app.run_test(size=size) as pilot:
            work = app.query_one(LongWork)
            assert work.start("training", job)
            await wait_for(pilot, lambda: "left" in work.text, 20, "a time left")
            said = [_left_s(work.text)]
            for _ in range(3):  # the clock goes on, no report: no news of a slower pace
                await pilot.pause(0.5)
                work._tick()
                said.append(_left_s(work.text))
            assert all(b <= a for a, b in zip(said, said[1:], strict=False)), said
            go.set()
            await wait_for(pilot, lambda: work.outcome == "done", 20, "done")

    asyncio.run(scenario())


def test_a_report_raises_it_by_noise_only_and_a_late_one_by_the_pace():
    t = [0.0]
    s = Steady(clock=lambda: t[0])
    assert s.left(10.0, report=True) == 10.0
    t[0] = 1.0
    assert s.left(12.0, report=False) == 9.0  # a tick: counts down
    t[0] = 2.0
    assert s.left(20.0, report=True) == 9.0  # a report: 8 s counted down + 1 s of noise
    t[0] = 3.0
    assert s.left(5.0, report=True) == 5.0  # faster: at once
    t[0] = 9.0
    assert s.left(4.0, report=False) == 4.0  # ran out (later than said): the pace stands
