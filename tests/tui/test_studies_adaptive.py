"""Issue 30: the Studies screen runs an adaptive protocol as it runs the experiments
(threshold_electrovibration, a simulated participant, at 80 x 24) and shows it live: the
plot of one track (its title the track), the trial count growing, the estimate, ``]``
cycling the tracks, and at the end where the threshold curve was saved."""

from __future__ import annotations

import asyncio
import json
import re
from pathlib import Path

from textual.widgets import ProgressBar

from console.cli.main import Context
from console.tui.app import HapTableApp

from .conftest import wait_for, words_on
from .test_camera_layout import text_in

#: threshold_electrovibration cut short: two tracks (sine, square at 120 Hz), 8 trials each
SHORT = Path(__file__).resolve().parents[2] / "studies" / "threshold_electrovibration.toml"


def short_protocol(tmp_path):
    text = SHORT.read_text()
    text = text.replace(
        "freq_hz = [15, 30, 60, 120, 240, 480, 960, 1920]", "freq_hz = [120]"
    ).replace("max_trials = 80", "max_trials = 8")
    text = text.replace("start_db = 36.0", "start_db = 26.0")
    text = text.replace(
        "threshold_db = { sine = [30.0, 27.0, 24.0, 22.0, 24.0, 26.0, 28.0, 30.0], "
        "square = [24.0, 23.0, 22.0, 22.0, 24.0, 26.0, 28.0, 30.0] }",
        "threshold_db = { sine = [22.0], square = [22.0] }",
    )
    path = tmp_path / "threshold_electrovibration.toml"
    path.write_text(text)
    return path


def test_adaptive_run_plotted_live_at_80x24(plugins, tmp_path):
    from plugins.studies import protocol as P

    proto = short_protocol(tmp_path)
    out = tmp_path / "runs"

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
            await wait_for(pilot, lambda: app.pane("studies") is not None, 30, "studies")
            pane = app.pane("studies")
            sel = pane.query_one("#protocol")
            assert "threshold_electrovibration" in P.available()
            sel.set_options([(n, n) for n in (*P.available(), str(proto))])
            await pilot.pause(0.2)
            sel.value = str(proto)
            pane.query_one("#out").value = str(out)
            pane.focus()
            await pilot.press("s")
            bar = pane.query_one("#study-progress", ProgressBar)
            plot = pane.query_one("#study-plot")
            await wait_for(pilot, lambda: (bar.progress or 0) >= 2, 60, "two trials")
            assert plot.display and not pane.query_one("#study-trials").display
            head = words_on(app, "#adaptive-head")
            assert "Hz (" in head and "/8 trials" in head, head
            # the plot follows the trial in play: its track drawn once it has an answer
            axes = lambda: "level (dB)" in text_in(app, plot)  # noqa: E731
            await wait_for(pilot, axes, 60, "a track with an answer in play")
            shown = text_in(app, plot)
            assert "level (dB)" in shown and "trial of the track" in shown, shown
            status = words_on(app, "#study-status")
            assert "P01" in status and "/16 trials done" in status, status
            first = int(bar.progress)
            await wait_for(pilot, lambda: (bar.progress or 0) > first, 60, "the count grows")
            assert f"{int(bar.progress)}/16 trials done" in words_on(app, "#study-status")
            before = words_on(app, "#adaptive-head")
            title = before.split(":")[0]
            await pilot.press("right_square_bracket")
            after = words_on(app, "#adaptive-head")
            # `]` picks the next track from the one shown when it came: the run may have
            # moved the view to its next track between the read above and the key
            assert "Hz (" in after and "picked with [ ]" in after, (before, after)
            run_on = re.search(r"the run is on (\S+ \(\d/\d\))", after)
            assert after.split(":")[0] != title or (run_on and run_on[1] != title), (before, after)
            assert "] track" in text_in(app, app.screen.query_one("Footer"))  # listed at 80
            await wait_for(pilot, lambda: pane.running is None, 120, "the run finished")
            status = words_on(app, "#study-status")
            assert "threshold curve saved to P01/thresholds.json" in status, status
            heads = []
            for _ in range(2):  # each track's estimate as the plot shows it
                heads.append(words_on(app, "#adaptive-head"))
                await pilot.press("right_square_bracket")
            assert all("done after 8 trials" in h for h in heads), heads
            assert any(re.search(r"threshold -?\d+\.\d dB \(mean of", h) for h in heads), heads

    asyncio.run(scenario())
    curve = json.loads((out / "P01" / "thresholds.json").read_text())
    assert curve["curves"] and curve["curves"][0]["modality"] == "electrovibration"


def test_a_person_answers_an_adaptive_trial_by_its_interval():
    """1..n answer (yes/no: 1 = yes, 2 = no); another key or a replay is refused in one
    line and the trial asks again."""
    from plugins.studies.adaptive_console import _person
    from plugins.studies.responders import QueueResponder
    from plugins.studies.runner import Answer, Control

    said = []
    t = {"trial": 4, "track": "sine_120Hz", "level_db": 20.0, "target_interval": 1}
    for task, keys, want in (("2afc", ["up", "2"], "2"), ("yes_no", ["1"], "yes")):
        q = QueueResponder()
        for k in keys:
            q.put(Answer(response=k))
        q.clear = lambda: None  # the answers are there before the trial asks
        got, rt = _person(q, Control(), task, lambda kind, d: said.append((kind, d)))(t, None)
        assert got == want and rt is not None
    refused = [d["why"] for kind, d in said if kind == "refused"]
    assert refused == ["up is no answer: answer 1..2: the interval"], refused
    assert [d["trial"]["condition"] for kind, d in said if kind == "ask"] == ["20.0 dB"] * 3
