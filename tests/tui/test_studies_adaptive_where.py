"""Studies, an adaptive run (threshold_vibrotactile's seven QUEST+ tracks, a simulated
participant) at 80 x 24 and 120 x 40: the plot follows the trial in play (the status's
``trial 10: sine_160Hz`` over ``sine_160Hz (4/7)``, never the track answered before),
and with a track picked with ``[`` / ``]`` the line above the plot says where the run
is, its track and trial whole on screen (a new operator read ``the run is on sine_16…``
at 120 columns and nothing of it at 80)."""

from __future__ import annotations

import asyncio

import pytest

from console.cli.main import Context
from console.plugin_api.runtime import Stopped
from console.plugin_api.tui import SessionMessage
from console.tui.app import HapTableApp
from plugins.studies.adaptive_console import TOPIC, trial_row

from .conftest import wait_for, words_on
from .test_camera_layout import SIZES, text_in

FREQS = (40, 70, 100, 160, 250, 400, 630)


def _track(i: int, levels: list[float]) -> dict:
    return {
        "track": f"sine_{FREQS[i]}Hz",
        "index": i,
        "count": len(FREQS),
        "freq_hz": float(FREQS[i]),
        "waveform": "sine",
        "reference": "dB re 1 um",
        "measure": "detection",
        "levels": levels,
        "correct": [True] * len(levels),
        "max_trials": 50,
        "done": False,
        "estimate_db": -0.2 if levels else None,
        "ci_db": [-29.0, 38.0],
        "reversals": [],
        "marginal": None,
        "method": "quest+",
    }


def _start(n: int, track: str) -> dict:
    return {"kind": "start", "trial": trial_row({"trial": n - 1, "track": track, "level_db": 2.0})}


@pytest.mark.parametrize("size", SIZES, ids=["80x24", "120x40"])
def test_the_plot_follows_the_trial_in_play_and_says_where_the_run_is(plugins, size):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=size) as pilot:
            await wait_for(pilot, lambda: app.pane("studies") is not None, 30, "studies")
            pane = app.pane("studies")
            await wait_for(
                pilot, lambda: "no study running" in words_on(app, "#study-status"), 30, "idle"
            )
            pane.query_one("#protocol").value = "threshold_vibrotactile"
            await pilot.pause(0.2)
            pane.running, pane.last = "P01", {"pid": "P01", "done": 8, "total": 350}
            pane._view("plot")
            tracks = [_track(i, [3.0] * 2 if i < 3 else []) for i in range(len(FREQS))]
            pane._snapshot({"kind": "tracks", "tracks": tracks})
            pane._snapshot(_start(9, "sine_100Hz"))
            pane._snapshot({"kind": "track", "track": _track(2, [3.0] * 3)})
            pane._snapshot({"kind": "progress", "done": 9, "total": 350})
            pane._snapshot(_start(10, "sine_160Hz"))
            await pilot.pause(0.2)
            status = words_on(app, "#study-status")
            head = pane.query_one("#adaptive-head")
            assert "trial 10: sine_160Hz" in status, status
            assert text_in(app, head).startswith("sine_160Hz (4/7)"), text_in(app, head)
            # a pick: the line above says where the run is, whole on the screen
            pane.focus()
            await pilot.press("left_square_bracket")
            await pilot.pause(0.2)
            shown = text_in(app, head)
            assert shown.startswith("sine_100Hz (3/7)"), shown
            assert "the run is on sine_160Hz (4/7), trial 10" in shown, shown
            # the run moves on: the line follows it, the plot stays on the pick
            pane._snapshot({"kind": "track", "track": _track(3, [2.0])})
            pane._snapshot(_start(11, "sine_250Hz"))
            await pilot.pause(0.2)
            shown = text_in(app, head)
            assert shown.startswith("sine_100Hz (3/7)"), shown
            assert "the run is on sine_250Hz (5/7), trial 11" in shown, shown
            # back to the run's track: the plot follows the run again
            for _ in range(2):
                await pilot.press("right_square_bracket")
            await pilot.pause(0.2)
            assert text_in(app, head).startswith("sine_250Hz (5/7)"), text_in(app, head)
            assert "the run is on" not in text_in(app, head)
            pane._snapshot(_start(12, "sine_400Hz"))
            await pilot.pause(0.2)
            assert text_in(app, head).startswith("sine_400Hz (6/7)"), text_in(app, head)
            # a pick when the run stops: no line says where it is any more
            await pilot.press("left_square_bracket")
            await pilot.pause(0.2)
            assert "the run is on sine_400Hz" in text_in(app, head), text_in(app, head)
            pane.on_session_message(SessionMessage(Stopped(TOPIC, name="P01", reason="aborted")))
            await pilot.pause(0.2)
            assert text_in(app, head).startswith("sine_250Hz (5/7)"), text_in(app, head)
            assert "the run is on" not in text_in(app, head), text_in(app, head)

    asyncio.run(scenario())
