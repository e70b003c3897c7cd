"""The Studies screen shows the choice made, not the run before it: another protocol
(or participant) brings that participant's saved progress of that protocol, or nothing
yet, into the progress bar, the status and the trials table; and a long run (the
1,280-trial electrovibration threshold, about half an hour) asks before it starts,
saying its size and time (a new operator's try: one ``s`` started it, under the
previous protocol's 36 % and trial table)."""

from __future__ import annotations

import asyncio
import json

import pytest

from .studies_pilot import studies_app, studies_pane, wait_for


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_another_protocol_shows_its_own_state_and_a_long_run_asks(
    double_plugins, map_file, tmp_path, size, long_runs_ask
):
    from textual.widgets import ProgressBar, Static

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            status = pane.query_one("#study-status", Static)
            bar = pane.query_one("#study-progress", ProgressBar)
            table = pane.query_one("#study-trials")
            pane.query_one("#protocol").value = "exp1"
            pane.query_one("#out").value = str(tmp_path)
            pane.query_one("#participant").value = "P02"
            pane.focus()
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.last.get("done", 0) >= 2, what="two trials")
            await pilot.press("a", "a")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            done = pane.last["done"]
            assert "stopped: aborted" in str(status.render()) and table.row_count == done

            pane.query_one("#protocol").value = "threshold_electrovibration"
            await wait_for(pilot, lambda: table.row_count == 0, 10, "exp1's trials gone")
            text = " ".join(str(status.render()).split())
            assert text.startswith("no study running"), text  # nothing of P02's yet
            assert "/50" not in text and "stopped" not in text
            assert (bar.progress or 0) == 0

            pane.focus()
            await pilot.press("s")  # a long run: it asks first, saying how long
            await pilot.pause(0.3)
            assert pane.running is None and not (tmp_path / "P02" / "adaptive.json").exists()
            said = " ".join(str(status.render()).split())
            assert (
                "s again within 5 s starts threshold_electrovibration with P02: "
                "up to 1,280 trials, about 30 min" in said
            ), said

            pane.query_one("#protocol").value = "exp1"  # back: P02's saved progress
            await wait_for(pilot, lambda: table.row_count == done, 10, "P02's exp1 trials")
            text = " ".join(str(status.render()).split())
            assert f"P02: {done}/50 trials done" in text, text
            assert f"s resumes P02 at trial {done + 1} of 50" in text
            assert bar.progress == done and bar.total == 50

            pane.query_one("#participant").value = "P09"  # typed: nothing of P09 yet
            await wait_for(pilot, lambda: table.row_count == 0, 10, "P02's trials gone")
            text = " ".join(str(status.render()).split())
            assert text.startswith("no study running") and "P02" not in text, text

            pane.query_one("#protocol").value = "threshold_electrovibration"
            pane.focus()
            await pilot.press("s", "s")  # the second starts it
            await wait_for(pilot, lambda: pane.running == "P09", 30, "the long run")
            await pilot.press("a", "a")
            await wait_for(pilot, lambda: pane.running is None, 30, "the run stopped")

    asyncio.run(scenario())


def test_the_size_of_a_fixed_run_comes_from_the_folder_s_earlier_runs(tmp_path, long_runs_ask):
    """A fixed plan's time is known from the trials its folder's runs took (the same
    kind of participant); without any, from its stimuli (a flow: the profile's two parts
    and their gap; a person also answers), and without those only its size is said."""
    from plugins.studies.saved_run import run_size

    assert run_size("exp2", tmp_path, "P01", True).words() == "200 trials"
    first = run_size("exp2", tmp_path, "P01", True, stimulus_s=3.1)
    assert first.seconds == 200 * 3.1 and first.long  # 10 min 20 s: it asks first
    assert first.words() == (
        "200 trials, at least 10 min 20 s (its stimuli play in real time, 3.1 s a trial)"
    )
    person = run_size("exp2", tmp_path, "P01", False, stimulus_s=3.1)
    assert person.seconds == 200 * 4.1
    d = tmp_path / "P01"
    d.mkdir()
    lines = [
        {"event": "done", "experiment": "exp2", "trial": i, "simulated": True}
        | {"t_start": 100.0 + 3 * i, "t_end": 102.0 + 3 * i}
        for i in range(5)
    ]
    (d / "trials.jsonl").write_text("".join(json.dumps(x) + "\n" for x in lines))
    size = run_size("exp2", tmp_path, "P02", True)
    assert size.seconds == 400.0 and size.long
    assert size.words() == (
        "200 trials, about 6 min 40 s (at the pace of the earlier runs in the folder, 2.0 s "
        "a trial)"
    )
    assert run_size("exp2", tmp_path, "P02", False).seconds is None  # a person: not known
    # the folder's pace wins over the stimuli's (its trials as long as them at least)
    assert run_size("exp2", tmp_path, "P02", True, stimulus_s=2.1).seconds == 400.0


def test_a_simulated_run_s_time_is_the_console_s_pace(tmp_path):
    """Issue 27: exp2 simulated said "200 trials, about 10 min (3 s a trial)" while the
    shell's simulated exp1 ran 0.5 s a trial. The shell's ``--simulate`` fast-forwards
    the twin; the console plays the stimuli in real time (3.1 to 4.6 s a trial measured
    on the twin), so the stimuli are the run's floor ("at least"), and trials shorter
    than their stimuli (a fast-forwarded run in the folder) are not the console's pace."""
    from plugins.studies.saved_run import run_size

    def trials(pid: str, took_s: float) -> None:
        d = tmp_path / pid
        d.mkdir()
        lines = [
            {"event": "done", "experiment": "exp2", "trial": i, "simulated": True}
            | {"t_start": 100.0 + 5 * i, "t_end": 100.0 + took_s + 5 * i}
            for i in range(5)
        ]
        (d / "trials.jsonl").write_text("".join(json.dumps(x) + "\n" for x in lines))

    trials("P07", 0.5)  # a shell's fast-forwarded run in the same folder
    size = run_size("exp2", tmp_path, "P01", True, stimulus_s=3.0)
    assert size.seconds == 600.0 and size.at_least, size
    assert size.words().startswith("200 trials, at least 10 min"), size.words()
    trials("P08", 4.0)
    trials("P09", 4.0)  # the console's runs: their pace is this run's
    size = run_size("exp2", tmp_path, "P01", True, stimulus_s=3.0)
    assert size.seconds == 800.0 and not size.at_least, size
    assert "about 13 min 20 s" in size.words(), size.words()


def test_a_saved_run_is_this_protocol_s_only(tmp_path):
    """What the screen shows of a folder: the participant's run of the chosen protocol
    (an adaptive one's logged trials too), never another protocol's run there."""
    from plugins.studies.saved_run import saved

    d = tmp_path / "P02"
    d.mkdir()
    (d / "adaptive.json").write_text(json.dumps({"experiment": "threshold_electrovibration"}))
    done = [
        {"event": "done", "trial": i, "track": "sine_60Hz", "level_db": 30.0 - i} for i in range(3)
    ]
    (d / "adaptive_trials.jsonl").write_text("".join(json.dumps(x) + "\n" for x in done))
    run = saved(tmp_path, "P02", "threshold_electrovibration")
    assert (run.done, run.total, len(run.records)) == (3, 1280, 3)
    assert saved(tmp_path, "P02", "exp1") is None  # no plan.json: no exp1 run
    assert saved(tmp_path, "P03", "threshold_electrovibration") is None
    (d / "plan.json").write_text(json.dumps({"experiment": "exp2", "trials": []}))
    assert saved(tmp_path, "P02", "exp1") is None  # exp2's plan: not exp1's


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_first_simulated_exp2_run_asks_first(
    double_plugins, map_file, tmp_path, size, long_runs_ask
):
    """Issue 27 (a new-user try): simulated exp2 in an empty folder, one ``s``: the 200
    trials (about 11 min on the twin) started at once; they ask first as every long run
    does, their time from the stimuli, and ``s`` again starts them."""
    from textual.widgets import Static

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=size) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            status = pane.query_one("#study-status", Static)
            pane.query_one("#protocol").value = "exp2"
            pane.query_one("#out").value = str(tmp_path)
            pane.query_one("#participant").value = "P01"
            pane.query_one("#simulate").value = True
            pane.focus()
            await pilot.press("s")
            await pilot.pause(0.3)
            said = " ".join(str(status.render()).split())
            assert pane.running is None and not (tmp_path / "P01" / "plan.json").exists(), said
            assert "s again within 5 s starts exp2 with P01: 200 trials, at least 10 min" in said
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.running == "P01", 30, "the run")
            await pilot.press("a", "a")
            await wait_for(pilot, lambda: pane.running is None, 30, "the run stopped")

    asyncio.run(scenario())
