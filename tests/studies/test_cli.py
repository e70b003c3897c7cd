"""``haptable study run`` as a user runs it: simulated participants, resume after kill -9,
one-line errors."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]


@pytest.fixture
def cli(double_plugins, monkeypatch):
    from console.cli.main import main

    return main


@pytest.fixture
def fast_twin():
    """The operator's override ``audio.paced = false`` for the sim profile: a person's run
    plays on the fast-forward twin (what these tests check is the typed answers, the stored
    files and the lines printed, not the playback's real time)."""
    from console.files.paths import profile_config_dir

    path = profile_config_dir("sim", "overrides.toml")
    path.parent.mkdir(parents=True, exist_ok=True)
    before = path.read_text() if path.exists() else None
    path.write_text("[audio]\npaced = false\n")
    yield
    # the config root lives for the worker's session: the next test gets it as it was
    if before is None:
        path.unlink(missing_ok=True)
    else:
        path.write_text(before)


def _done(d: Path) -> list[dict]:
    lines = [json.loads(x) for x in (d / "trials.jsonl").read_text().splitlines() if x.strip()]
    return [e for e in lines if e["event"] == "done"]


def test_simulated_participants_run_exp2_and_resume(cli, capsys, tmp_path, map_file, small_exp2):
    out = tmp_path / "study"
    args = ["study", "run", str(small_exp2), "--simulate", "--participants", "2", "--out", str(out)]
    args += ["--map", str(map_file)]
    assert cli([*args, "--trials", "4", "--json"]) == 0
    first = json.loads(capsys.readouterr().out)
    assert [p["participant"] for p in first["participants"]] == ["P01", "P02"]
    assert [p["done"] for p in first["participants"]] == [4, 4]
    assert cli(args) == 0  # the same command continues
    text = capsys.readouterr().out
    assert "P01: 6/6 trials done (finished)" in text and "P02: 6/6 trials done (finished)" in text
    # said before the run, and each trial's line says how far the run is: the resume
    # runs the 2 trials left of 6
    assert f"P01: exp2 -> {out / 'P01'}: 2 trial(s) to run" in text
    assert re.search(r"P01 trial 5: .*\[5/6", text) and re.search(r"P01 trial 6: .*\[6/6\]", text)
    for pid in ("P01", "P02"):
        d = out / pid
        part = json.loads((d / "participant.json").read_text())
        assert part["simulated"] and part["observer"]["model"] == "test double"
        assert {
            "age",
            "sex",
            "handedness",
            "hand_width_cm",
            "hand_length_cm",
            "consent_noted",
        } <= set(part)
        plan = json.loads((d / "plan.json").read_text())
        assert plan["experiment"] == "exp2" and len(plan["trials"]) == 6 and plan["protocol_sha256"]
        done = _done(d)
        assert [e["trial"] for e in done] == list(range(6))
        assert all(e["response"] in ("up", "down", "left", "right") for e in done)
        assert all(e["simulated"] and e["region"] in ("Rprelim", "R4") for e in done)


def test_a_person_needs_their_details_and_consent(
    cli, capsys, tmp_path, map_file, small_exp2, monkeypatch, fast_twin
):
    monkeypatch.setattr(sys.stdin, "isatty", lambda: False)
    base = ["study", "run", str(small_exp2), "--participant", "P01", "--out", str(tmp_path)]
    base += ["--map", str(map_file)]
    assert cli(base) == 2
    err = capsys.readouterr().err
    assert "participant P01: give --age, --sex, --handedness" in err and err.count("\n") == 1
    details = ["--age", "31", "--sex", "male", "--handedness", "left"]
    details += ["--hand-width-cm", "8.2", "--hand-length-cm", "18"]
    assert cli([*base, *details]) == 2
    assert "consent" in capsys.readouterr().err
    assert not (tmp_path / "P01" / "plan.json").exists()  # nothing stored for a refused start
    # typed answers (a keypad: 8 = up, 0 = replay)
    keys = iter(["0", "8", "x", "6", "8", "2", "4", "6"])
    monkeypatch.setattr("builtins.input", lambda prompt="": next(keys))
    assert cli([*base, *details, "--consent"]) == 0
    out = capsys.readouterr().out
    assert "P01 trial 1: answered (1 replay(s))" in out
    assert "correct" not in out and "wrong" not in out  # the participant may read it
    done = _done(tmp_path / "P01")
    assert len(done) == 6 and done[0]["replays"] == 1 and done[0]["response"] == "up"
    part = json.loads((tmp_path / "P01" / "participant.json").read_text())
    assert part["consent_noted"] is True and part["handedness"] == "left" and not part["simulated"]


def test_input_that_ends_is_bad_input_not_ctrl_c_and_the_resume_says_where(
    cli, capsys, tmp_path, map_file, small_exp2, monkeypatch, fast_twin
):
    """A script's answers run out (stdin closed): exit 2 with one line, not 130 (Ctrl-C);
    the same command then says in one line where it resumes."""
    monkeypatch.setattr(sys.stdin, "isatty", lambda: False)
    base = ["study", "run", str(small_exp2), "--participant", "P01", "--out", str(tmp_path)]
    base += ["--map", str(map_file), "--age", "31", "--sex", "F", "--handedness", "L"]
    base += ["--hand-width-cm", "8.2", "--hand-length-cm", "18", "--consent"]

    def answers(*keys):
        it = iter(keys)

        def read(prompt=""):
            try:
                return next(it)
            except StopIteration:
                raise EOFError from None

        return read

    monkeypatch.setattr("builtins.input", answers("8", "6"))
    assert cli(base) == 2
    cap = capsys.readouterr()
    assert cap.err.count("\n") == 1 and cap.err.startswith("haptable: error: input ended")
    assert "P01's trial 3" in cap.err and "resumes" in cap.err
    part = json.loads((tmp_path / "P01" / "participant.json").read_text())
    assert (part["sex"], part["handedness"]) == ("female", "left")  # F and L accepted
    monkeypatch.setattr("builtins.input", answers("8", "2", "4", "6"))
    assert cli(base) == 0
    out = capsys.readouterr().out
    line = "P01: resuming at trial 3 of 6 (2 done; trial 3 was interrupted and runs again)"
    assert out.count(line) == 1
    assert [e["trial"] for e in _done(tmp_path / "P01")] == list(range(6))


def test_errors_are_one_line(cli, capsys, tmp_path):
    assert cli(["study", "run", "exp9", "--participant", "P01", "--out", str(tmp_path)]) == 2
    assert "no protocol of that name" in capsys.readouterr().err
    assert cli(["study", "run", "exp1", "--participants", "3", "--out", str(tmp_path)]) == 2
    assert "add --simulate" in capsys.readouterr().err


def test_study_list_shows_the_counts(cli, capsys):
    assert cli(["study", "list"]) == 0
    out = capsys.readouterr().out
    assert re.search(r"^ +exp1 +50  familiarisation 10, main 40 +Experiment 1", out, re.M)
    assert re.search(r"^ +exp2 +200  preliminary 40, main 160 +Experiment 2", out, re.M)
    assert re.search(r"^ +knob +216  main 216 ", out, re.M)


SCRIPT = """
import sys
sys.path.insert(0, {here!r})
from console.config import plugins as cp
cp.BUILTIN_PLUGINS["double"] = "observer_double"
from console.cli.main import main
sys.exit(main({args!r}))
"""


def test_kill_9_mid_trial_marks_it_interrupted_and_repeats_it(tmp_path, map_file, small_exp2):
    out = tmp_path / "study"
    args = ["study", "run", str(small_exp2), "--simulate", "--participant", "P03"]
    args += ["--out", str(out), "--map", str(map_file), "--quiet"]
    script = SCRIPT.format(here=str(HERE), args=args)
    hang = tmp_path / "hanging"
    env = {
        **os.environ,
        "PYTHONPATH": str(ROOT),
        "HAPTABLE_TEST_HANG_AT": "3",
        "HAPTABLE_TEST_HANG_FILE": str(hang),
    }
    proc = subprocess.Popen([sys.executable, "-c", script], env=env, cwd=ROOT)
    try:
        for _ in range(1200):
            if hang.exists() or proc.poll() is not None:
                break
            time.sleep(0.1)
        assert hang.exists(), "the run never reached trial 4"
        proc.send_signal(signal.SIGKILL)
        proc.wait(30)
    finally:
        if proc.poll() is None:
            proc.kill()
    d = out / "P03"
    events = [json.loads(x) for x in (d / "trials.jsonl").read_text().splitlines()]
    assert [e["event"] for e in events][-1] == "start" and events[-1]["trial"] == 3
    assert [e["trial"] for e in events if e["event"] == "done"] == [0, 1, 2]
    # the same command again (the double no longer hangs: its file exists)
    done = subprocess.run(
        [sys.executable, "-c", script], env=env, cwd=ROOT, timeout=600, capture_output=True
    )
    assert done.returncode == 0, done.stderr
    assert "P03: resuming at trial 4 of 6 (3 done; trial 4 was interrupted and runs again)" in (
        done.stdout.decode()
    )
    events = [json.loads(x) for x in (d / "trials.jsonl").read_text().splitlines()]
    kinds = [(e["event"], e["trial"]) for e in events]
    assert kinds[6:9] == [("start", 3), ("interrupted", 3), ("start", 3)]
    assert [e["trial"] for e in events if e["event"] == "done"] == list(range(6))


def test_simulated_knob_runs_the_knob_task_then_the_questionnaire(cli, capsys, tmp_path):
    out = tmp_path / "knob"
    args = ["study", "run", "knob", "--simulate", "--participant", "P02", "--out", str(out)]
    assert cli([*args, "--trials", "54", "--quiet"]) == 0  # the first condition
    d = out / "P02"
    plan = json.loads((d / "plan.json").read_text())
    assert plan["latin_square_row"] == 1
    first = plan["questionnaires"][0]["condition"]
    done = _done(d)
    assert len(done) == 54 and {e["condition"] for e in done} == {first}
    for e in done:
        assert e["response"] is None and e["overshoots"] >= 0
        assert e["sectors"] in (8, 16, 32) and e["distance_deg"] in (135.0, 270.0, 450.0)
        assert e["correct"] == (not e["timed_out"])
        if not e["timed_out"]:
            assert e["completion_time_s"] > 0
    lines = [json.loads(x) for x in (d / "trials.jsonl").read_text().splitlines()]
    qs = [e for e in lines if e["event"] == "questionnaire"]
    assert len(qs) == 14 and {q["condition"] for q in qs} == {first}
    assert all(1 <= q["score"] <= 7 for q in qs)
    part = json.loads((d / "participant.json").read_text())
    assert part["simulated"] and "simulated finger" in part["observer"]["model"]
