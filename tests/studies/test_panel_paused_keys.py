"""Studies while paused (a new operator's try): ``r`` answers on the status line, the
footer offers ``p resume`` (it read ``p pause``), the footer names every button's key in
the buttons' order (Replay was left out), and a stopped run's status names the
participant (``stopped: aborted: 8/50 done`` did not)."""

from __future__ import annotations

import asyncio

import pytest

from .studies_pilot import wait_for
from .test_panel_issue27 import _app, _running

SIZES = [(80, 24), (120, 40)]
IDS = ["80x24", "120x40"]


def _status(pane) -> str:
    return " ".join(str(pane.query_one("#study-status").render()).split())


def _footer(app) -> str:
    return app.screen._compositor.render_strips()[-1].text


@pytest.mark.parametrize("size", SIZES, ids=IDS)
def test_the_footer_names_every_button_and_p_says_resume_while_paused(
    double_plugins, map_file, tmp_path, size
):
    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await _running(pilot, app, map_file, tmp_path)
            await wait_for(pilot, lambda: "r replay" in _footer(app), 5, "replay in the footer")
            footer = _footer(app)
            keys = [footer.find(k) for k in ("s start", "p pause", "r replay", "a abort")]
            assert -1 not in keys and keys == sorted(keys), footer  # the buttons' order
            assert "t view" in footer, footer  # 80 columns: n gives r its place in a run
            await pilot.press("p")
            await wait_for(pilot, lambda: pane.control.paused, 5, "paused")
            await wait_for(pilot, lambda: "p resume" in _footer(app), 10, "p resumes")
            await pilot.press("p")  # resumed: p pauses again
            await wait_for(pilot, lambda: "p pause" in _footer(app), 10, "p pauses")
            pane.control.abort("test over")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            # no run: n analyses in r's place, r (nothing to replay) answers off the footer
            await wait_for(pilot, lambda: "n analyse" in _footer(app), 5, "n in the footer")
            assert "r replay" not in _footer(app) and "t view" in _footer(app), _footer(app)
            await pilot.press("r")
            await wait_for(pilot, lambda: "nothing to replay" in _status(pane), 5, "r answers")

    asyncio.run(scenario())


@pytest.mark.parametrize("size", SIZES, ids=IDS)
def test_paused_r_answers_and_the_stop_names_the_participant(
    double_plugins, map_file, tmp_path, size
):
    async def scenario():
        app = _app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await _running(pilot, app, map_file, tmp_path)
            await pilot.press("p", "r")  # r as the pause takes hold: its answer stays
            await wait_for(pilot, lambda: "paused (p resumes)" in _status(pane), 10, "paused")
            assert "r: " in _status(pane), _status(pane)
            await pilot.press("r")  # paused: no stimulus waits, r says so
            await wait_for(pilot, lambda: "r: paused" in _status(pane), 5, "r answered")
            await pilot.press("a", "a")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            await wait_for(pilot, lambda: "run stopped: aborted" in _status(pane), 10, "said")
            assert "P01's run stopped: aborted" in _status(pane), _status(pane)

    asyncio.run(scenario())
