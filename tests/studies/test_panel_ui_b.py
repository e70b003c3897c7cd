"""The Studies screen, issue 27 (ui b), at 80 x 24 in one simulated run of a small
protocol: the count of trials says the time left; the experimenter's last key's outcome
goes once the run moves on ("resumed" leaves with the next trial) and a newer key's
question replaces it ("r: paused ..." does not come back when the ``a`` question
expires); the protocol list shows its Enter first in the footer; the finished run is analysed at once, so ``t`` shows its analysis without
``n``."""

from __future__ import annotations

import asyncio

from .conftest import SMALL_EXP2
from .studies_pilot import pick_protocol, studies_app, studies_pane, wait_for

#: four trials: one preliminary, three main
FOUR_TRIALS = SMALL_EXP2.replace('direction = ["up", "right"]', 'direction = ["up"]').replace(
    'direction = ["up", "down", "left", "right"]', 'direction = ["up", "down", "left"]'
)


def _footer(app) -> str:
    """The terminal's last line: the footer, as drawn."""
    return app.screen._compositor.render_strips()[-1].text


def test_time_left_outcomes_lapse_and_analysis_at_once(
    double_plugins, map_file, tmp_path, monkeypatch
):
    from textual.widgets import ProgressBar

    from plugins.studies import panel as studies_panel
    from plugins.studies import panel_status

    monkeypatch.setattr(studies_panel, "CONFIRM_S", 1.0)
    # a key's answer holds the line 5 s at least: short here, the four trials end sooner
    monkeypatch.setattr(panel_status, "ANSWER_HOLD_S", 0.3)
    protocol = tmp_path / "exp2-four.toml"
    protocol.write_text(FOUR_TRIALS)

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            await pick_protocol(pilot, pane, protocol, tmp_path / "runs")
            # the protocol list focused: named, its own key (Enter) first in the footer
            pane.query_one("#protocol").focus()
            await wait_for(pilot, lambda: "protocols" in _footer(app), 30, "footer")
            assert _footer(app).split()[:3] == ["protocol:", "⏎", "protocols"], _footer(app)
            pane.focus()
            status = pane.query_one("#study-status")

            def shown() -> str:
                return str(status.render())

            await pilot.press("s")
            bar = pane.query_one("#study-progress", ProgressBar)
            await wait_for(pilot, lambda: (bar.progress or 0) >= 2, what="two trials")
            await wait_for(pilot, lambda: " left" in shown(), 30, "the time left")
            assert "trials done, " in shown() and "left" in shown().splitlines()[0], shown()
            # paused, r says why nothing happens; a asks: its question replaces the r line
            await pilot.press("p")
            await wait_for(pilot, lambda: "paused (p resumes)" in shown(), 30, "paused")
            await pilot.press("r")
            assert "r: paused" in shown(), shown()
            await pilot.press("a")
            assert "a again within" in shown() and "r: paused" not in shown(), shown()
            await wait_for(pilot, lambda: "a again" not in shown(), 10, "question expired")
            assert "r: paused" not in shown(), shown()  # not back: a newer key spoke
            # resumed: said until the next trial starts, then gone
            await pilot.press("p")
            await wait_for(pilot, lambda: "resumed" not in shown(), 30, "resumed gone")
            assert pane.running == "P01", shown()  # gone while the run goes on
            await wait_for(pilot, lambda: pane.running is None, what="finished")
            assert "finished" in pane.last["stopped"]
            # t at once: the finished run's analysis, not an empty view
            await pilot.press("t")
            view = pane.query_one("#study-analysis")
            assert view.display
            head = pane.query_one("#analysis-head")
            await wait_for(pilot, lambda: pane.notes, 60, "the analysis in")
            assert "analysing" not in str(head.render()), str(head.render())
            assert "exp2" in str(head.render()) or pane.notes, str(head.render())

    asyncio.run(scenario())
