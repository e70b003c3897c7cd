"""The Studies screen as an experimenter uses it (Textual's Pilot): experiment 2 for a
simulated participant, progress moving, abort, and a resume that continues where it
stopped."""

from __future__ import annotations

import asyncio
import json
import re

from .studies_pilot import pick_protocol, studies_app, studies_pane, wait_for


def _events(path):
    return [json.loads(x) for x in path.read_text().splitlines() if x.strip()]


def test_exp2_simulated_from_the_screen_abort_and_resume(double_plugins, map_file, tmp_path):
    from textual.widgets import DataTable, ProgressBar, Static

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            pane.query_one("#protocol").value = "exp2"
            pane.query_one("#out").value = str(tmp_path)
            assert pane.query_one("#simulate").value is True
            await pilot.click("#start")
            bar = pane.query_one("#study-progress", ProgressBar)
            await wait_for(pilot, lambda: (bar.progress or 0) >= 3, what="three trials done")
            assert bar.total == 200
            status = str(pane.query_one("#study-status", Static).render())
            assert "P01" in status and "/200 trials done" in status and "Rprelim" in status
            await pilot.click("#abort")  # asks first
            await pilot.pause(0.4)  # a click in the button's 0.2 s press effect is no press
            await pilot.click("#abort")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            stopped_at = int(bar.progress)
            assert "aborted" in str(pane.query_one("#study-status", Static).render())
            events = _events(tmp_path / "P01" / "trials.jsonl")
            done = [e["trial"] for e in events if e["event"] == "done"]
            assert done == list(range(len(done))) and len(done) == stopped_at
            table = pane.query_one("#study-trials", DataTable)
            assert table.row_count == stopped_at
            # start again: the stored plan continues at the next trial
            await pilot.click("#start")
            await wait_for(pilot, lambda: (bar.progress or 0) >= stopped_at + 2, what="resumed")
            await pilot.click("#abort")  # asks first
            await pilot.pause(0.4)  # a click in the button's 0.2 s press effect is no press
            await pilot.click("#abort")
            await wait_for(pilot, lambda: pane.running is None, what="stopped again")
            events = _events(tmp_path / "P01" / "trials.jsonl")
            starts = [e["trial"] for e in events if e["event"] == "start"]
            done = [e["trial"] for e in events if e["event"] == "done"]
            assert done == list(range(len(done))) and len(done) >= stopped_at + 2
            n_first = len([e for e in starts if e < stopped_at]) + 1  # + the aborted one
            assert starts[n_first - 1] == stopped_at or starts[n_first] == stopped_at
            plan = json.loads((tmp_path / "P01" / "plan.json").read_text())
            for e in events:
                if e["event"] == "done":
                    t = plan["trials"][e["trial"]]
                    assert (e["region"], e["direction"]) == (t["region"], t["direction"])

    asyncio.run(scenario())


def test_a_person_answers_with_the_keys_and_replays_once(
    double_plugins, map_file, tmp_path, small_exp2
):
    from textual.widgets import ProgressBar

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            await pick_protocol(pilot, pane, small_exp2, tmp_path)
            pane.query_one("#simulate").value = False
            await pilot.click("#start")  # no details: refused in one line, nothing stored
            await wait_for(
                pilot, lambda: pane.running is None and pane.last.get("stopped"), what="refused"
            )
            assert (  # every missing field at once, as the screen names them
                "participant P01: age, sex, handedness, hand width cm and hand length cm "
                "missing; give them and note the consent (tick 'consent noted')"
                in pane.last["stopped"]
                and not (tmp_path / "P01").exists()
            )
            for wid, v in (
                ("age", "28"),
                ("sex", "female"),
                ("handedness", "right"),
                ("hand_width_cm", "8.4"),
                ("hand_length_cm", "18.1"),
            ):
                pane.query_one(f"#{wid}").value = v
            pane.query_one("#consent").value = True
            start = pane.query_one("#start")  # a second click during the first's press
            await wait_for(
                pilot, lambda: not start.has_class("-active"), 5, "pressed"
            )  # is not one
            await pilot.click("#start")
            bar = pane.query_one("#study-progress", ProgressBar)
            for k, key in enumerate(["up", "right", "2", "left", "8", "6"]):  # 2 8 6: keypad
                await wait_for(pilot, lambda: pane.asking is not None, what=f"asked {k}")
                pane.focus()
                if k == 2:  # one replay allowed in the main phase, a second is refused
                    await pilot.press("r")
                    await wait_for(  # the replay, or already its wait for the answer after it
                        pilot,
                        lambda: (
                            pane.last.get("state") == "replay 1"
                            or "0 replay(s) left" in str(pane.last.get("state"))
                        ),
                        what="replay",
                    )
                    await wait_for(pilot, lambda: pane.asking is not None, what="asked again")
                await pilot.press(key)
                await wait_for(pilot, lambda k=k: (bar.progress or 0) >= k + 1, what=f"answer {k}")
            await wait_for(pilot, lambda: pane.running is None, what="finished")
            events = _events(tmp_path / "P01" / "trials.jsonl")
            done = [e for e in events if e["event"] == "done"]
            assert [e["response"] for e in done] == ["up", "right", "down", "left", "up", "right"]
            assert [e["replays"] for e in done][2] == 1
            assert all(e["response_time_s"] > 0 for e in done)
            assert "finished" in pane.last["stopped"]

    asyncio.run(scenario())


def test_a_person_answers_on_the_projected_arrows_the_camera_sees(
    double_plugins, map_file, tmp_path, small_exp2
):
    """Fig. 12b: the hand guide on the trial's region and four projected arrows; the twin
    camera sees the operator's finger on an arrow and that is the answer."""

    small_exp2.write_text(
        small_exp2.read_text().replace("seed = 3", 'seed = 3\nscene = "flow_hand"')
    )

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            await pick_protocol(pilot, pane, small_exp2, tmp_path)
            pane.query_one("#simulate").value = False
            pane.query_one("#projector").value = True
            for wid, v in (
                ("age", "28"),
                ("sex", "male"),
                ("handedness", "left"),
                ("hand_width_cm", "8.4"),
                ("hand_length_cm", "18.1"),
            ):
                pane.query_one(f"#{wid}").value = v
            pane.query_one("#consent").value = True
            await pilot.pause(0.2)
            await pilot.click("#start")
            want = ["up", "left", "down", "right", "left", "up"]
            for k, d in enumerate(want):
                await wait_for(pilot, lambda: pane.asking is not None, 120, f"asked {k}")
                svc = app.session.projector
                state = svc.scene.state()
                assert state["region"] == pane.last["trial"]["region"]
                assert state["hand_outline_mm"] and not state["playing"]
                (button,) = [b for b in state["buttons"] if b["dir"] == d]
                cam = app.session.camera.camera
                cam.set_target(tuple(button["c"]))
                await wait_for(
                    pilot,
                    lambda k=k: len(pane.query_one("#study-trials").rows) > k,
                    60,
                    f"touch {k}",
                )
                cam.set_target(None)
                await pilot.pause(0.3)
            await wait_for(pilot, lambda: pane.running is None, 60, "finished")
            done = [e for e in _events(tmp_path / "P01" / "trials.jsonl") if e["event"] == "done"]
            assert [e["response"] for e in done] == want

    asyncio.run(scenario())


def test_a_person_s_knob_trials_run_on_the_camera_then_the_questionnaire(
    double_plugins, tmp_path, monkeypatch
):
    """Knob trials with a person from the screen: each streams through the outputs while
    the console's camera loop feeds it (on the twin nobody turns it: it times out), then
    the participant scores the 14 items with 1..7."""
    from plugins.studies import protocol as P
    from plugins.studies import stimuli

    monkeypatch.setattr(stimuli, "LIVE_KNOB_MAX_S", 0.5)
    text = P.find("knob").read_text().replace("repetitions = 6", "repetitions = 2")
    text = text.replace('["V", "HD", "HD+CF", "HD+VF"]', '["HD+CF"]')
    text = text.replace("sectors = [8, 16, 32]", "sectors = [8]").replace(
        "[135, 270, 450]", "[135]"
    )
    path = tmp_path / "knob-small.toml"
    path.write_text(text)
    hooked = []

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await studies_pane(pilot, app)
            await pick_protocol(pilot, pane, path, tmp_path)
            pane.query_one("#simulate").value = False
            pane.query_one("#projector").value = True  # the knob and its menu (Fig. 16a)
            for wid, v in (
                ("age", "40"),
                ("sex", "other"),
                ("handedness", "right"),
                ("hand_width_cm", "9"),
                ("hand_length_cm", "19"),
            ):
                pane.query_one(f"#{wid}").value = v
            pane.query_one("#consent").value = True
            await pilot.pause(0.2)
            await pilot.click("#start")
            await wait_for(pilot, lambda: app.session.camera.frame_hooks, 60, "camera hooked")
            hooked.append(len(app.session.camera.frame_hooks))
            for k in range(14):
                await wait_for(
                    pilot, lambda: pane.asking and "item" in pane.asking, 60, f"item {k}"
                )
                if k == 0:  # the projector shows the last trial's knob: 8 sectors, 135 deg
                    svc = app.session.projector
                    st = svc.scene.state()
                    assert svc.scene_name == "knob" and st["sectors"] == 8
                    assert st["target"] - svc.scene.start == 3
                    # the camera feeds the projected buttons' watcher and the live knob
                    hooked.append(len(app.session.camera.frame_hooks))
                pane.focus()
                await pilot.press(str(1 + k % 7))
            await wait_for(pilot, lambda: pane.running is None, 60, "finished")
            assert "finished" in pane.last["stopped"]
            assert not app.session.camera.frame_hooks  # the camera hook went with the run
            assert pane.query_one("#participant").value == "P02"  # ready for the next one

    asyncio.run(scenario())
    events = _events(tmp_path / "P01" / "trials.jsonl")
    done = [e for e in events if e["event"] == "done"]
    assert len(done) == 2 and all(e["timed_out"] and not e["correct"] for e in done)
    assert all(e["condition"] == "HD+CF" and e["response"] is None for e in done)
    qs = [e for e in events if e["event"] == "questionnaire"]
    assert sorted(q["score"] for q in qs) == sorted(1 + k % 7 for k in range(14))
    assert hooked[-1] == 2


def test_the_e_stop_stops_a_run_and_its_trial_is_repeated(double_plugins, map_file, tmp_path):
    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            pane.query_one("#protocol").value = "exp1"
            pane.query_one("#out").value = str(tmp_path)
            await pilot.click("#start")
            await wait_for(pilot, lambda: pane.last.get("done", 0) >= 1, what="a trial done")
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")
            assert "e-stop" in pane.last["stopped"]
            assert not app.session.outputs.status()["busy"]
            assert app.session.outputs.estopped

    asyncio.run(scenario())
    events = _events(tmp_path / "P01" / "trials.jsonl")
    assert events[-1]["event"] == "interrupted" and "e-stop" in events[-1]["reason"]
    assert events[-2] == {**events[-2], "event": "start", "trial": events[-1]["trial"]}


def test_the_next_participant_id():
    from plugins.studies.panel_text import next_id

    assert [next_id(p) for p in ("P01", "P09", "S099", "P1", "alice")] == [
        "P02",
        "P10",
        "S100",
        "P2",
        "alice",
    ]


def test_analyse_writes_the_report_and_shows_the_anova(double_plugins, tmp_path):
    """n on the Studies screen at 80 x 24: the folder's runs of the chosen protocol (an exp1
    run in the same folder is left aside), the report next to them, the ANOVA table shown
    whole on screen (the key result, region * direction, too), the notes in one line (o
    shows them all), the footer's keys with ^e and ? beside them. A failed analysis (a
    folder without runs, a file, a folder that does not exist) is its line alone: no table
    of the analysis before it."""
    import sys
    from pathlib import Path

    from textual.widgets import DataTable, Static

    from .test_panel_readable import screen_text

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import synth_runs as sr

    def weak(i, region, direction):
        return 0.5 if (region == "R4" and direction == "right") else 0.95

    sr.write_flow(tmp_path / "runs", "exp2", ("R1", "R2", "R3", "R4"), weak, 6, 6, seed=2)
    sr.write_flow(tmp_path / "x", "exp1", ("1",), lambda *a: 1.0, 1, 1)
    (tmp_path / "x" / "P01").rename(tmp_path / "runs" / "Q01")
    (tmp_path / "empty").mkdir()
    (tmp_path / "a-file").write_text("x")

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(80, 24)) as pilot:
            await wait_for(pilot, lambda: app.pane("studies") is not None, what="studies")
            pane = app.pane("studies")
            pane.query_one("#protocol").value = "exp2"
            pane.query_one("#out").value = str(tmp_path / "runs")
            table = pane.query_one("#study-anova", DataTable)
            head = pane.query_one("#analysis-head", Static)
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="focus on Start")
            await pilot.press("n")
            await wait_for(
                pilot, lambda: table.row_count == 3, what="the ANOVA table", timeout_s=120
            )
            assert pane.query_one("#study-analysis").display
            assert not pane.query_one("#study-trials").display
            report = tmp_path / "runs" / "exp2-report.html"
            assert str(head.render()).startswith("exp2: 6 participant(s), 6 simulated; accuracy")
            assert "<h1>HapTable study: exp2</h1>" in report.read_text()
            rows = [[str(c) for c in table.get_row_at(i)] for i in range(3)]
            effects = {r[0]: r for r in rows}
            inter = effects["region * direction"]
            assert inter[2].endswith(" GG") == (inter[3] != "assumed")
            assert float(inter[1].split()[0]) > 2  # the weak R4 cell: an interaction
            # what the screen shows at 80 x 24: every row, the notes line, the report
            await pilot.pause(0.3)
            text = screen_text(app)
            lines = text.splitlines()
            for effect, row in effects.items():
                assert any(
                    ln.strip().startswith(effect) and row[1] in ln and row[2] in ln for ln in lines
                ), (effect, text)
            assert "report: exp2-report.html in the folder" in [ln.strip() for ln in lines]
            assert re.search(r"^\d+ notes? \(o shows all\): ", text, re.M), text
            footer = lines[-1]
            for key in ("s start", "p pause", "a abort", "n analyse", "t view", "^e E-STOP"):
                assert key in footer, footer
            assert "? help" in footer, footer
            # o: the notes in the table's place, and back
            await pilot.press("o")
            await pilot.pause(0.2)
            text = screen_text(app)
            assert "notes (" in text and "region * direction" not in text
            assert "accuracy (main phase) " in text and "participants: P01, P02" in text
            await pilot.press("o")
            await pilot.pause(0.2)
            assert "region * direction" in screen_text(app)
            await pilot.press("t")
            assert pane.query_one("#study-trials").display
            await pilot.press("t")
            assert pane.query_one("#study-analysis").display
            # failed analyses: one line each, the table of the analysis before gone
            for folder, why in (
                ("empty", "no participant folder"),
                ("a-file", "is a file, not a folder"),
                ("missing", "no such folder"),
            ):
                pane.query_one("#out").value = str(tmp_path / folder)
                await pilot.press("n")
                await wait_for(pilot, lambda why=why: why in str(head.render()), what=why)
                shown = str(head.render())
                assert shown.startswith(f"analysis: {tmp_path / folder}: {why}")
                assert shown.endswith(
                    "set folder to the study's results folder (the one holding P01/ ...)"
                )
                assert len(shown.splitlines()) == 1 and "--out" not in shown
                assert table.row_count == 0
                await pilot.pause(0.2)
                text = screen_text(app)
                assert "region * direction" not in text and "report: " not in text, text
                # the next good analysis brings the table back
                pane.query_one("#out").value = str(tmp_path / "runs")
                await pilot.press("n")
                await wait_for(pilot, lambda: table.row_count == 3, what="again", timeout_s=120)

    asyncio.run(scenario())


def test_each_protocol_has_its_default_folder(double_plugins):
    from textual.widgets import Input

    from console.files import paths

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.pane("studies") is not None, what="studies")
            pane = app.pane("studies")
            out = pane.query_one("#out", Input)
            first = pane.query_one("#protocol").value
            assert out.value == str(paths.data_dir("studies", first))
            pane.query_one("#protocol").value = "exp2"
            await pilot.pause()
            assert out.value == str(paths.data_dir("studies", "exp2"))
            out.value = "/data/lab/my-study"  # typed: kept whatever the protocol
            pane.query_one("#protocol").value = "knob"
            await pilot.pause()
            assert out.value == "/data/lab/my-study"

    asyncio.run(scenario())


def test_a_console_killed_mid_trial_resumes_from_the_screen(double_plugins, map_file, tmp_path):
    """The console process killed with SIGKILL while a trial plays; a new console's
    Studies screen starts the same participant: the trial in flight is marked interrupted
    and repeated, the stored plan goes on, and the outputs open (no stale lock)."""
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    from textual.widgets import ProgressBar

    here = Path(__file__).resolve().parent
    out, hang = tmp_path / "runs", tmp_path / "hanging"
    env = {
        **os.environ,
        "PYTHONPATH": str(here.parents[1]),
        "HAPTABLE_TEST_HANG_AT": "4",
        "HAPTABLE_TEST_HANG_FILE": str(hang),
    }
    child = [sys.executable, str(here / "console_child.py"), str(out), str(map_file)]
    proc = subprocess.Popen(child, env=env, cwd=here.parents[1])
    try:
        for _ in range(1800):
            if hang.exists() or proc.poll() is not None:
                break
            time.sleep(0.1)
        assert hang.exists(), f"the console never reached trial 5 (exit {proc.poll()})"
        proc.send_signal(signal.SIGKILL)
        assert proc.wait(30) == -signal.SIGKILL
    finally:
        if proc.poll() is None:
            proc.kill()
    events = _events(out / "P01" / "trials.jsonl")
    assert [e["trial"] for e in events if e["event"] == "done"] == [0, 1, 2, 3]
    assert (events[-1]["event"], events[-1]["trial"]) == ("start", 4)
    plan_before = (out / "P01" / "plan.json").read_text()

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await studies_pane(pilot, app, map_file)
            pane.query_one("#protocol").value = "exp2"
            pane.query_one("#out").value = str(out)
            await wait_for(pilot, lambda: app.focused is pane.focus_target, what="focus on Start")
            await pilot.press("s")
            bar = pane.query_one("#study-progress", ProgressBar)
            await wait_for(pilot, lambda: (bar.progress or 0) >= 7, what="resumed to trial 7")
            await pilot.press("a", "a")  # the second confirms
            await wait_for(pilot, lambda: pane.running is None, what="the run stopped")

    asyncio.run(scenario())
    assert (out / "P01" / "plan.json").read_text() == plan_before  # the stored plan
    events = _events(out / "P01" / "trials.jsonl")
    kinds = [(e["event"], e["trial"]) for e in events]
    assert kinds[8:11] == [("start", 4), ("interrupted", 4), ("start", 4)]
    done = [e["trial"] for e in events if e["event"] == "done"]
    assert done[:7] == list(range(7)) and done == sorted(set(done))


def test_a_flow_study_measures_its_map_pauses_on_the_next_trial_and_refreshes_the_analysis(
    double_plugins, tmp_path, small_exp2
):
    """No vibration map yet: the status says so before s, and s measures it first (as
    `haptable study run` does). Pausing shows the trial that comes next. The analysis
    shown for the folder is marked stale while the run writes to it and analysed again
    when it stops. A refused start after it shows no stale progress."""
    from textual.widgets import DataTable, ProgressBar, Static

    async def scenario():
        app = studies_app(double_plugins)
        async with app.run_test(size=(120, 40)) as pilot:
            pane = await studies_pane(pilot, app)
            await pick_protocol(pilot, pane, small_exp2, tmp_path)
            status = pane.query_one("#study-status", Static)
            head = pane.query_one("#analysis-head", Static)
            await wait_for(pilot, lambda: "needs a vibration map" in str(status.render()), 10)
            assert "s measures the twin's grid first" in str(status.render())
            assert app.session.vibration.current is None
            pane.focus()
            await pilot.press("n")  # nothing in the folder yet
            await wait_for(pilot, lambda: "no participant folder" in str(head.render()), 30)
            await pilot.press("s")
            seen = []
            for _ in range(1200):
                seen.append(str(status.render()))
                if pane.last.get("done", 0) >= 1:
                    break
                await pilot.pause(0.05)
            assert any("vibration map: " in x for x in seen), seen[:5]
            assert app.session.vibration.current is not None  # measured, now the console's
            assert str(head.render()).startswith(f"stale: P01's run is writing to {tmp_path}")
            await pilot.press("p")
            await wait_for(pilot, lambda: pane.last.get("state") == "paused (p resumes)", 60)
            await pilot.pause(0.2)
            done = [e for e in _events(tmp_path / "P01" / "trials.jsonl") if e["event"] == "done"]
            plan = json.loads((tmp_path / "P01" / "plan.json").read_text())
            nxt = plan["trials"][len(done)]
            shown = str(status.render())
            from plugins.studies.panel_text import trial_text

            assert f"next: trial {len(done) + 1}: {trial_text(nxt)}" in shown, shown
            await pilot.press("a", "a")  # the second confirms
            await wait_for(pilot, lambda: pane.running is None, what="stopped")
            # the analysis shown before the run is done again, with the run in it
            await wait_for(pilot, lambda: str(head.render()).startswith("exp2: 1 participant"), 60)
            assert pane.query_one("#study-trials").display  # the view the experimenter had
            assert pane.query_one("#study-anova", DataTable).row_count == 0  # missing cells
            await pilot.press("t")
            assert pane.query_one("#study-analysis").display
            # a refused start: no progress left over from the run before
            bar = pane.query_one("#study-progress", ProgressBar)
            assert (bar.progress or 0) >= 1
            pane.query_one("#participant").value = "P02"
            pane.query_one("#simulate").value = False
            await pilot.press("s")
            await wait_for(pilot, lambda: pane.running is None and "P02" in str(status.render()))
            await pilot.pause(0.2)
            assert (bar.progress or 0) == 0
            shown = str(status.render())
            assert shown.startswith("P02: not started") and "0/0" not in shown, shown

    asyncio.run(scenario())
