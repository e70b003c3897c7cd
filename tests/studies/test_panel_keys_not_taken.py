"""Issue 27: keys pressed during a person's trial were dropped without a word: a burst
``1 2 1 2 1 2`` in exp1 answered one trial and the other five left no status line and no
log entry. A key that is not taken says why (the answer already given, the stimulus still
playing) on the status line, under the run's state, and in the log."""

from __future__ import annotations

import asyncio
import json
import logging

import pytest

from .studies_pilot import studies_app, studies_pane, wait_for
from .test_panel_estop_while_waiting import _status, _waiting


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_burst_of_answers_says_why_the_rest_are_not_taken(
    double_plugins, map_file, tmp_path, size, caplog
):
    caplog.set_level(logging.INFO, "haptable.console")

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            await _waiting(pilot, app, pane, tmp_path)
            await pilot.press("1", "2", "1", "2", "1", "2")
            await wait_for(pilot, lambda: pane.last.get("done", 0) >= 1, 10, "one answered")

            def refused_now() -> list:
                return [r for r in caplog.records if "not taken" in r.getMessage()]

            # every key of the burst an answer or a word why not (a next trial's stimulus
            # may already have ended when the last keys come: they answer it)
            def accounted() -> int:
                return int(pane.last.get("done", 0)) + len(refused_now())

            await wait_for(pilot, lambda: accounted() >= 6, 10, "every key answered")
            await pilot.pause(0.3)
            refused, done = refused_now(), int(pane.last.get("done", 0))
            assert done + len(refused) == 6, (done, [r.getMessage() for r in refused])
            assert refused, "no key of the burst was refused"
            words = ("already answered", "answer after the stimulus")
            assert all(any(w in r.getMessage() for w in words) for r in refused), refused
            text = _status(pane)
            assert f"P01: {done}/50 trials done" in text and f"trial {done + 1}:" in text, text
            path = tmp_path / "P01" / "trials.jsonl"
            events = [json.loads(ln) for ln in path.read_text().splitlines()]
            assert len([e for e in events if e["event"] == "done"]) == done
            pane.control.abort("test over")
            await wait_for(pilot, lambda: pane.running is None, 10, "the run stopped")

    asyncio.run(scenario())


def test_a_digit_with_no_run_says_so(double_plugins, tmp_path, caplog):
    caplog.set_level(logging.INFO, "haptable.console")

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await studies_pane(pilot, app)
            pane.focus()
            await pilot.press("1")
            await wait_for(pilot, lambda: "no study running" in _status(pane), 10, "said")
            assert "1: no study running" in caplog.text

    asyncio.run(scenario())
