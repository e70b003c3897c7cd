"""Issue 30: a study with a level in dB SL starts from the Studies screen as from the
command line: the participant's level is resolved before the first trial (plan.json keeps
the volts and the threshold used), not refused because the screen is not the CLI."""

from __future__ import annotations

import asyncio
import json

from textual.widgets import ProgressBar

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on

KNOB_SL = """
[study]
name = "knob"
stimulus = "knob"
responses = []
seed = 5
level = "10 dB SL"
[[phases]]
name = "main"
factors = { condition = ["HD"], sectors = [16], distance_deg = [135] }
repetitions = 1
"""


def test_a_knob_study_in_db_sl_runs_from_the_screen(plugins, tmp_path):
    from plugins.studies import protocol as P

    proto = tmp_path / "knob-sl.toml"
    proto.write_text(KNOB_SL)
    out = tmp_path / "runs"

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: app.pane("studies") is not None, 30, "studies")
            pane = app.pane("studies")
            sel = pane.query_one("#protocol")
            sel.set_options([(n, n) for n in (*P.available(), str(proto))])
            await pilot.pause(0.2)
            sel.value = str(proto)
            pane.query_one("#out").value = str(out)
            pane.focus()
            await pilot.press("s")
            bar = pane.query_one("#study-progress", ProgressBar)
            await wait_for(
                pilot,
                lambda: (bar.progress or 0) >= 1 or "refused" in words_on(app, "#study-status"),
                90,
                "a trial or a refusal",
            )
            status = words_on(app, "#study-status")
            assert "level" not in status or "refused" not in status, status
            plans = list(out.glob("*/plan.json"))
            assert plans, status
            trial = json.loads(plans[0].read_text())["trials"][0]
            parts = trial["stimulus"]["level"]["parts"]
            assert parts and all(p["amplitude_v"] > 0 for p in parts), trial["stimulus"]

    asyncio.run(scenario())
