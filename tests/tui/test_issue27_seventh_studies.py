"""Issue 27, seventh new-user try, finding 4 (Studies, 120 x 40): the status follows a
protocol change, the plot names a track as the status does (the protocol's name), a
track picked with ] stays while the run goes on elsewhere, and the trials table's time
column is whole."""

from __future__ import annotations

import asyncio

from console.cli.main import Context
from console.tui.app import HapTableApp
from plugins.studies.adaptive_console import trial_row
from plugins.studies.adaptive_view import AdaptiveView
from plugins.studies.trials_table import TrialsTable

from ..studies.studies_pilot import studies_idle
from .conftest import wait_for, words_on


def _screen(app) -> str:
    return "\n".join(strip.text for strip in app.screen._compositor.render_strips())


def _track(name: str, index: int, freq_hz: float, levels: list[float]) -> dict:
    return {
        "track": name,
        "index": index,
        "count": 2,
        "freq_hz": freq_hz,
        "waveform": name.split("_")[0],
        "reference": "dB re 1 V peak",
        "measure": "detection",
        "levels": levels,
        "correct": [True] * len(levels),  # (a view with other levels says its own)
        "max_trials": 8,
        "done": False,
        "estimate_db": None,
        "ci_db": None,
        "reversals": [],
        "marginal": None,
        "method": "staircase",
        "used_reversals": 0,
        "stop_reversals": 4,
    }


def test_status_plot_names_picked_track_and_time_column_at_120(plugins):
    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await studies_idle(app, pilot)
            status = lambda: words_on(app, "#study-status")  # noqa: E731
            # a refusal about the protocol before stays no longer than that protocol
            pane._say("exp1 needs a vibration map: measure one on Vibration (F3)", "error")
            assert "exp1 needs a vibration map" in status()
            pane.query_one("#protocol").value = "jnd_amplitude"
            await wait_for(pilot, lambda: "jnd_amplitude chosen" in status(), 30, "status")
            assert "exp1 needs a vibration map" not in status()
            # the trials table: every column whole at 120 columns, the time too
            table = pane.query_one("#study-trials", TrialsTable)
            what = "main: from 36 to 76 (PB, PC) right, sine 250 Hz 40 V, hand flat " * 2
            for i in range(3):
                table.add_trial(str(i + 1), what, "right", "yes", "0", f"{1.25 + i:.2f} s")
            await wait_for(pilot, lambda: "3.25 s" in _screen(app), 30, "the time shown")
            assert table.virtual_size.width <= table.size.width
            # the plot: the protocol's names; a pick stays while the run is elsewhere
            view = pane.query_one(AdaptiveView)
            a, b = _track("square_60Hz", 0, 60.0, [20.0]), _track("square_120Hz", 1, 120.0, [])
            view.snapshot({"kind": "tracks", "tracks": [a, b]})
            view.snapshot({"kind": "track", "track": a})
            trial = trial_row({"trial": 1, "track": "square_60Hz", "level_db": 18.0})
            head = words_on(app, "#adaptive-head")
            assert head.startswith("square_60Hz (1/2)") and trial["phase"] == "square_60Hz"
            pane.focus()
            await pilot.press("right_square_bracket")
            await wait_for(
                pilot,
                lambda: words_on(app, "#adaptive-head").startswith("square_120Hz"),
                30,
                "picked",
            )
            view.snapshot(
                {"kind": "track", "track": {**a, "levels": [20.0, 18.0], "correct": [True, True]}}
            )
            await pilot.pause()
            head = words_on(app, "#adaptive-head")
            assert head.startswith("square_120Hz (2/2)"), head  # the pick, not the run
            assert "the run is on square_60Hz" in head, head
            await pilot.press("left_square_bracket")  # back on the run's: it follows again
            view.snapshot({"kind": "track", "track": {**b, "levels": [30.0], "correct": [True]}})
            await pilot.pause()
            assert words_on(app, "#adaptive-head").startswith("square_120Hz (2/2)")

    asyncio.run(scenario())
