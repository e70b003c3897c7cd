"""A study recorded per trial (``haptable study run ... --record``): kill -9 mid-study
leaves the earlier trials readable, the same command appends without a second copy, the
whole recording replays "the same", and a tampered trial is named."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pytest

from console.plugin_api import UserError

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]


@pytest.fixture
def cli(double_plugins):
    from console.cli.main import main

    return main


def _run_args(small_exp2, out, map_file, pid="P01"):
    args = ["study", "run", str(small_exp2), "--simulate", "--participant", pid]
    return [*args, "--out", str(out), "--map", str(map_file), "--quiet", "--record"]


def test_bad_replay_input_is_one_line(cli, capsys, tmp_path):
    assert cli(["study", "replay", str(tmp_path / "nothing")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "no such file or folder" in err
    junk = tmp_path / "trial_0000.h5"
    junk.write_text("not hdf5")
    from plugins.studies.trial_replay import read_trial

    with pytest.raises(UserError, match="not an HDF5 file"):
        read_trial(junk)


SCRIPT = """
import sys
sys.path.insert(0, {here!r})
from console.config import plugins as cp
cp.BUILTIN_PLUGINS["double"] = "observer_double"
from console.cli.main import main
sys.exit(main({args!r}))
"""


def test_kill_9_mid_study_keeps_earlier_trials_and_resume_appends(
    cli, capsys, tmp_path, map_file, small_exp2
):
    out = tmp_path / "study"
    script = SCRIPT.format(here=str(HERE), args=_run_args(small_exp2, out, map_file, "P03"))
    hang = tmp_path / "hanging"
    env = {**os.environ, "PYTHONPATH": str(ROOT), "HAPTABLE_TEST_HANG_AT": "3"}
    env["HAPTABLE_TEST_HANG_FILE"] = str(hang)
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
    rec = out / "P03" / "recording"
    assert sorted(p.name for p in rec.glob("trial_*.h5")) == [f"trial_{i:04d}.h5" for i in range(3)]
    from plugins.studies.trial_replay import read_trial

    assert [read_trial(rec / f"trial_{i:04d}.h5")["done"]["trial"] for i in range(3)] == [0, 1, 2]
    before = {i: (rec / f"trial_{i:04d}.h5").read_bytes() for i in range(3)}
    capsys.readouterr()
    assert cli(_run_args(small_exp2, out, map_file, "P03")) == 0  # the same command resumes
    assert "P03: 6/6 trials done (finished)" in capsys.readouterr().out
    assert sorted(p.name for p in rec.iterdir() if not p.name.startswith("map")) == [
        f"trial_{i:04d}.h5" for i in range(6)
    ]  # one file per trial, no leftover .part
    assert all((rec / f"trial_{i:04d}.h5").read_bytes() == before[i] for i in range(3))
    with h5py.File(rec / "trial_0002.h5", "r") as f:
        trial = json.loads(f["trial"][()])
        done = json.loads(f["done"][()])
        plans = [json.loads(x) for x in f["outputs"][()].decode().splitlines()]
    assert trial["index"] == 2 and trial["stimulus"]["effect"] == "hand_flow"
    assert done["response"] in ("up", "down", "left", "right") and done["response_time_s"] > 0
    assert plans and plans[0]["kind"] == "plan" and len(plans[0]["hash"]) == 64
    assert plans[0]["segment_end"] and plans[0]["error"] == ""  # the kernel's report clocks

    capsys.readouterr()
    assert cli(["replay", str(rec)]) == 0
    assert "replay: 6 trials of exp2 (P03) the same" in capsys.readouterr().out

    # the stimulus of trial 5 edited in its file: re-rendered, it is another plan
    with h5py.File(rec / "trial_0004.h5", "r+") as f:
        t = json.loads(f["trial"][()])
        t["stimulus"]["direction"] = {"up": "down"}.get(t["stimulus"]["direction"], "up")
        del f["trial"]
        f.create_dataset("trial", data=json.dumps(t))
    assert cli(["study", "replay", str(out)]) == 1
    line = capsys.readouterr().out.strip()
    assert line.startswith("replay: first difference at trial 5 (P03, trial_0004.h5): plan 1")


def test_a_trial_that_sees_the_camera_keeps_its_frames_and_an_interrupted_one_none(tmp_path):
    import numpy as np

    from console.plugin_api import Frame
    from plugins.studies.trial_recording import TrialRecorder
    from plugins.studies.trial_replay import read_trial

    (tmp_path / "plan.json").write_text("{}")
    trials = [{"index": i, "phase": "main", "stimulus": {"effect": "hand_flow"}} for i in (0, 1)]
    rec = TrialRecorder(tmp_path, {"experiment": "exp2", "trials": trials}, profile=None)
    images = [np.full((48, 64), 10 * k, np.uint8) for k in range(3)]
    rec.begin(0)
    for k, im in enumerate(images):
        rec.frame(Frame(im, k, 0.1 * k, source="twin"), {})
    path = rec.finish({"trial": 0, "participant": "P01", "event": "done", "response": "up"})
    rec.begin(1)
    rec.frame(Frame(images[0], 9, 0.9, source="twin"), {})
    rec.discard()  # an aborted trial: no file, no leftover part
    assert sorted(p.name for p in (tmp_path / "recording").iterdir()) == [path.name]
    got = read_trial(path)
    assert got["frames"] == 3 and got["done"]["response"] == "up"
    with h5py.File(path, "r") as f:
        assert np.array_equal(f["frames"][2], images[2]) and list(f["t_capture_s"]) == [0, 0.1, 0.2]


def test_a_recorded_trial_opens_where_haptable_replay_reads_it(
    cli, capsys, tmp_path, map_file, small_exp2, double_plugins
):
    """What ``haptable replay`` reads the console's recording view opens (F9/F2 ``o``):
    a study run's trial file, with the plans the trial handed its outputs."""
    from console.tui.recording_view import open_run

    out = tmp_path / "study"
    assert cli(_run_args(small_exp2, out, map_file, "P03")) == 0
    trial = out / "P03" / "recording" / "trial_0000.h5"
    capsys.readouterr()
    assert cli(["replay", str(trial)]) == 0
    assert "1 trials" in capsys.readouterr().out
    run = open_run(double_plugins, str(trial))
    try:
        assert [p for p in run.plans() if p.get("kind") == "plan"], run.plans()
    finally:
        run.close()
