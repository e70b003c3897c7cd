"""The console's log (``ctrl+l``) holds what an operator needs to reconstruct a session,
as README says: every status line's news (not only warnings and errors), timestamped;
the e-stop and its reset; starts and stops of what runs (demos, scenes, measurements,
study runs). A status line's ticks (the same words with new numbers) are not repeated."""

from __future__ import annotations

import asyncio
import logging
import re

import pytest

from console.cli.main import Context
from console.session.events import Progress, Snapshot, Started, Stopped
from console.tui.app import HapTableApp
from console.tui.logs import ViewHandler
from console.tui.said import PROGRESS_S, log_status
from console.tui.session_log import ECHO_S, event_line, log_event

from .conftest import wait_for
from .test_screens import _ready

STAMP = re.compile(r"^\d{4}-\d\d-\d\d \d\d:\d\d:\d\d,\d{3} ")


def _status(app) -> str:
    return str(app.query_one("#es-status").render())


def _index(lines: list[str], *words: str) -> int:
    for i, line in enumerate(lines):
        if all(w in line for w in words):
            return i
    raise AssertionError(f"no log line with {words}:\n" + "\n".join(lines))


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_log_holds_status_lines_and_the_estop_in_order(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="electrostatic")
        view = ViewHandler(app)  # the log view's lines (``capture_logs`` in the console)
        logging.getLogger().addHandler(view)
        try:
            async with app.run_test(size=size) as pilot:
                await _ready(app, pilot)
                await pilot.press("p")
                await wait_for(pilot, lambda: _status(app).startswith("played"), 30, "played")
                await pilot.press("ctrl+e")
                await wait_for(pilot, lambda: app.session.outputs.estopped, 20, "e-stopped")
                await pilot.press("p")
                await wait_for(pilot, lambda: "refused" in _status(app), 20, "refused")
                await pilot.press("ctrl+r")
                await wait_for(pilot, lambda: not app.session.outputs.estopped, 20, "reset")
                await pilot.pause(0.3)
        finally:
            logging.getLogger().removeHandler(view)
        lines = list(view.lines)
        said = [ln for ln in lines if "haptable.console" in ln]
        assert said and all(STAMP.match(ln) for ln in said), said  # each with its time
        order = [
            _index(lines, "status Electrostatic: asking to play"),
            _index(lines, "status Electrostatic: played"),
            _index(lines, "E-STOP"),
            _index(lines, "status Electrostatic:", "refused: e-stop active"),
            _index(lines, "e-stop reset"),
        ]
        assert order == sorted(order), "\n".join(lines)
        assert "INFO" in lines[order[1]]  # news, not only warnings and errors

    asyncio.run(scenario())


def test_a_status_line_s_ticks_are_logged_once_its_news_each_time(caplog):
    caplog.set_level(logging.INFO, "haptable.console")
    where = "Tick test"
    assert log_status(where, "measuring: 3 %, 40 s left", now=0.0)
    assert not log_status(where, "measuring: 4 %, 39 s left", now=1.0)  # a tick
    assert not log_status(where, "measuring: 4 %, 39 s left", now=1.1)  # a redraw
    assert log_status(where, "point 51 played", now=2.0)  # news
    assert log_status(where, "measuring: 9 %, 30 s left", now=3.0)
    assert log_status(where, "measuring: 80 %, 3 s left", now=3.0 + PROGRESS_S)  # now and then
    said = [r.getMessage() for r in caplog.records if where in r.getMessage()]
    assert len(said) == 4, said


def test_starts_and_stops_are_news_snapshots_and_the_camera_following_screens_are_not():
    assert event_line(Started("demo", "flow", detail="running")) == (
        "demo flow running",
        "information",
    )
    assert event_line(Stopped("demo", "flow", reason="stopped"))[0] == "demo flow stopped: stopped"
    assert event_line(Stopped("estop", reason="operator e-stop (console)")) == (
        "E-STOP: operator e-stop (console)",
        "warning",
    )
    assert event_line(Started("estop", detail="reset by the console"))[0].startswith("e-stop reset")
    assert event_line(Started("study", "P01", detail="exp1 -> runs"))[0] == "study P01 exp1 -> runs"
    assert event_line(Snapshot("demo", "flow")) is None
    assert event_line(Progress("vibration", "measure", 0.3)) is None
    assert event_line(Started("camera")) is None
    assert event_line(Stopped("camera", reason="nobody watches")) is None
    assert event_line(Stopped("camera", reason="in use by demo flow")) is not None


def test_an_estop_heard_twice_is_logged_once():
    """The console's ctrl+e is reported by the session and again by the table's kernel."""
    ev = Stopped("estop", reason="operator e-stop (console)")
    assert log_event(ev, now=1000.0)
    assert not log_event(ev, now=1000.05)
    assert log_event(Started("estop", detail="reset"), now=1001.0)
    assert log_event(ev, now=1002.0)  # a second e-stop after the reset
    assert log_event(ev, now=1002.0 + ECHO_S)
