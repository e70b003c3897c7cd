"""Adaptive threshold runs recorded per trial (issue 31), as a user runs them: ``haptable
study run PROTOCOL --simulate --record`` leaves one readable file per trial (its trial as
the procedure proposed it, the plan played with the kernel's clocks, the kernel's relay
switches in the trial's window of gate clocks), a stopped run resumed by the same
command adds the missing trials without touching the others, ``haptable replay`` says
they replay the same and names a tampered trial; the Studies screen's "record trials"
switch records a run started there."""

from __future__ import annotations

import asyncio
import json

import h5py
import pytest

SMALL = """
[study]
name = "rec_quest"
seed = 5

[stimulus]
modality = "electrovibration"
reference = "dB re 1 V"
freq_hz = [120]
waveforms = ["sine"]
interval_s = 0.05
ramp_ms = 10
gap_s = 0.05

[procedure]
method = "quest+"
task = "2afc"
max_trials = 3
levels_db = [10.0, 40.0, 2.0]
thresholds_db = [10.0, 40.0, 2.0]
slopes = [2.0, 4.0]
lapses = [0.0, 0.02]

[observer]
threshold_db = [24.0]
"""


@pytest.fixture
def proto(tmp_path):
    p = tmp_path / "rec_quest.toml"
    p.write_text(SMALL)
    return p


def _done(root):
    lines = (root / "adaptive_trials.jsonl").read_text().splitlines()
    return [e for e in map(json.loads, lines) if e["event"] == "done"]


def test_an_adaptive_run_records_each_trial_resumes_and_replays_the_same(proto, tmp_path, capsys):
    from console.cli.main import main
    from plugins.studies.trial_replay import read_trial

    out = tmp_path / "out"
    argv = ["study", "run", str(proto), "--simulate", "--participant", "P01"]
    argv += ["--out", str(out), "--quiet", "--record"]
    assert main([*argv, "--trials", "2"]) == 0  # stopped after 2: the same command resumes
    rec = out / "P01" / "recording"
    first = {i: (rec / f"trial_{i:04d}.h5").read_bytes() for i in range(2)}
    assert main(argv) == 0
    assert sorted(p.name for p in rec.iterdir()) == [f"trial_{i:04d}.h5" for i in range(3)]
    assert all((rec / f"trial_{i:04d}.h5").read_bytes() == first[i] for i in range(2))

    done = _done(out / "P01")
    windows = []
    for i, d in enumerate(done):
        t = read_trial(rec / f"trial_{i:04d}.h5")
        assert t["attrs"]["kind"] == "adaptive" and t["attrs"]["trial_index"] == i
        want = {k: d[k] for k in ("trial", "track", "level_db", "target_interval")}
        assert t["trial"]["adaptive"] == want  # what the log says the procedure proposed
        assert t["done"]["response"] == d["response"]
        (plan,) = [x for x in t["outputs"] if x["kind"] == "plan"]
        assert plan["name"].endswith(f"trial {i + 1}") and plan["segment_end"]
        lo, hi = t["attrs"]["gate_clock_start"], t["attrs"]["gate_clock_end"]
        switches = [e for e in t["gate_events"] if e["kind"] == "switch"]
        assert len(switches) == 2  # the screen's relay closed for the trial, then opened
        assert all(lo <= e["clock"] <= hi for e in t["gate_events"])
        assert lo <= plan["segment_start"][0] <= plan["segment_end"][-1] <= hi
        windows.append((lo, hi))
    assert windows[0][1] <= windows[1][0]  # one run's trials one after the other

    capsys.readouterr()
    assert main(["replay", str(rec)]) == 0
    line = capsys.readouterr().out.strip()
    assert line.startswith("replay: 3 trials of rec_quest (P01) the same")
    assert line.endswith("6 gate events (6 relay switches) recorded")

    with h5py.File(rec / "trial_0001.h5", "r+") as f:  # another level in trial 2's file
        t = json.loads(f["trial"][()])
        t["adaptive"]["level_db"] += 2.0
        del f["trial"]
        f.create_dataset("trial", data=json.dumps(t))
    assert main(["replay", str(rec)]) == 1
    line = capsys.readouterr().out.strip()
    assert line.startswith("replay: first difference at trial 2 (P01, trial_0001.h5): plan 1")


def test_the_studies_screen_switch_records_the_trials(plugins, tmp_path):
    from textual.widgets import Checkbox

    from console.cli.main import Context
    from console.tui.app import HapTableApp
    from plugins.studies.trial_replay import replay_study

    out = tmp_path / "screen"
    proto = tmp_path / "rec_quest.toml"
    proto.write_text(SMALL.replace("max_trials = 3", "max_trials = 2"))  # 2 trials: enough

    async def wait_for(pilot, cond, what, timeout_s=60.0):
        for _ in range(int(timeout_s / 0.05)):
            if cond():
                return
            await pilot.pause(0.05)
        raise AssertionError(f"{what} not reached in {timeout_s:g} s")

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="studies")
        async with app.run_test(size=(120, 40)) as pilot:
            await wait_for(pilot, lambda: app.session.outputs is not None, "outputs")
            await wait_for(pilot, lambda: app.pane("studies") is not None, "studies")
            pane = app.pane("studies")
            sel = pane.query_one("#protocol")
            sel.set_options([(str(proto), str(proto))])
            await pilot.pause(0.2)
            sel.value = str(proto)
            pane.query_one("#out").value = str(out)
            switch = pane.query_one("#record", Checkbox)
            assert switch.value is False and "record trials" in str(switch.label)
            await pilot.click("#record")
            assert switch.value is True
            pane.query_one("#start").press()  # the button itself (a toast may cover it)
            await wait_for(pilot, lambda: pane.running is not None, "the run started")
            await wait_for(pilot, lambda: pane.running is None, "the run ended")

    asyncio.run(scenario())
    rec = out / "P01" / "recording"
    assert sorted(p.name for p in rec.iterdir()) == [f"trial_{i:04d}.h5" for i in range(2)]
    same, line = replay_study(rec, Context("sim", plugins))
    assert same, line
    assert "2 trials of rec_quest (P01) the same" in line and "4 relay switches" in line
