"""``haptable study run`` with an adaptive protocol as a user runs it: kill -9 mid-run,
the same command resumes with the same posterior and next level, the curve is saved."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]

SMALL_QUEST = """
[study]
name = "small_quest"
seed = 5

[stimulus]
modality = "electrovibration"
reference = "dB re 1 V"
freq_hz = [120]
waveforms = ["sine"]
interval_s = 0.1
ramp_ms = 10
gap_s = 0.05

[procedure]
method = "quest+"
task = "2afc"
max_trials = 14
levels_db = [10.0, 40.0, 1.0]
thresholds_db = [10.0, 40.0, 1.0]
slopes = [2.0, 4.0]
lapses = [0.0, 0.02]

[observer]
threshold_db = [24.0]
"""


def _events(d: Path) -> list[dict]:
    text = (d / "adaptive_trials.jsonl").read_text()
    return [json.loads(x) for x in text.splitlines() if x.strip().endswith("}")]


def test_kill_9_mid_run_resumes_with_the_same_posterior_and_next_level(tmp_path):
    from console.plugin_api import Limits, load_plugins, load_profile
    from plugins.studies import adaptive_protocol as ap
    from plugins.studies.adaptive_run import make_setup, next_trial, posterior_path, rebuild
    from plugins.studies.thresholds import load_curves

    proto_file = tmp_path / "small_quest.toml"
    proto_file.write_text(SMALL_QUEST)
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "console.cli.main", "study", "run", str(proto_file)]
    cmd += ["--simulate", "--participant", "P01", "--out", str(out), "--quiet"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    d = out / "P01"
    proc = subprocess.Popen(cmd, env=env, cwd=ROOT, start_new_session=True)
    try:
        for _ in range(3000):
            ev = _events(d) if (d / "adaptive_trials.jsonl").exists() else []
            if sum(e["event"] == "done" for e in ev) >= 4 and ev[-1]["event"] == "start":
                break
            assert proc.poll() is None, "the run ended before it could be killed"
            time.sleep(0.02)
        os.killpg(proc.pid, signal.SIGKILL)  # the run and anything it started
        proc.wait(30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    before = _events(d)
    done = [e for e in before if e["event"] == "done"]
    assert before[-1]["event"] == "start" and len(done) >= 4
    # the state the log rebuilds: the last posterior file and the next trial
    proto = ap.load(proto_file)
    setup = make_setup(proto, Limits.from_profile(load_profile(None, load_plugins())))
    seed = json.loads((d / "adaptive.json").read_text())["seed"]
    state = rebuild(setup, d, seed)
    saved = np.load(posterior_path(d, done[-1]["track"], done[-1]["trial"]))
    assert np.array_equal(state.procs["sine_120Hz"].posterior, saved)
    want = next_trial(setup, state, seed)
    cut = before[-1]
    assert {k: cut[k] for k in want} == want  # the trial in flight is the one proposed again
    # the same command: the interrupted trial again, same level and target, to the end
    res = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert res.returncode == 0, res.stderr
    after = _events(d)[len(before) :]
    assert after[0]["event"] == "interrupted" and after[0]["trial"] == cut["trial"]
    assert {k: after[1][k] for k in want} == want and after[1]["event"] == "start"
    trials = [e["trial"] for e in _events(d) if e["event"] == "done"]
    assert trials == list(range(14))
    assert len(list((d / "posterior" / "sine_120Hz").glob("*.npy"))) == 14
    (curve,) = load_curves(d)
    assert curve["modality"] == "electrovibration" and curve["freq_hz"] == [120.0]
    lo, hi = curve["ci_db"][0]
    assert lo <= curve["threshold_db"][0] <= hi and curve["procedure"] == "quest+ 2afc weibull"
    truth = json.loads((d / "participant.json").read_text())["observer"]["tracks"]["sine_120Hz"]
    assert abs(curve["threshold_db"][0] - truth["threshold_db"]) < 8  # 14 trials: roughly


def test_a_run_says_its_size_before_it_starts():
    """16 tracks of at most 80 2AFC trials (two 0.5 s intervals, a 0.4 s gap, ~1 s to
    answer): a person's run says 1280 trials and up to 51 min before the first."""
    from plugins.studies import adaptive_protocol as ap

    proto = ap.load(ROOT / "studies" / "threshold_electrovibration.toml")
    assert proto.size_line() == (
        "at most 1280 trials (16 tracks x 80), about 2.4 s each: up to 51 min"
    )
    assert proto.size_line(person=False) == "at most 1280 trials (16 tracks x 80)"
