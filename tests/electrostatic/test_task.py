"""The knob task: design, metrics, crash-safe log, simulated finger."""

import json

import numpy as np
import pytest

from console.core.errors import UserError
from console.files.atomic import append_json_line
from plugins.electrostatic.settings import knob_settings
from plugins.electrostatic.task import (
    SimFinger,
    make_trials,
    run_task,
    run_trial,
    trial_metrics,
)
from plugins.electrostatic.trial_log import read_trials


def test_the_paper_design_has_216_trials_in_a_fixed_random_order():
    tr = make_trials()
    assert len(tr) == 216
    keys = {(t.condition, t.sectors, t.distance_deg) for t in tr}
    assert len(keys) == 4 * 3 * 3
    assert [t.condition for t in tr] == [t.condition for t in make_trials()]  # same for all
    assert [t.condition for t in tr[:20]] != [t.condition for t in make_trials(seed=2)[:20]]
    t8 = next(t for t in tr if t.sectors == 8 and t.distance_deg == 450.0)
    assert t8.target_item - t8.start_item == 10  # 450 deg / 45 deg
    t32 = next(t for t in tr if t.sectors == 32 and t.distance_deg == 135.0)
    assert t32.target_item - t32.start_item == 12
    with pytest.raises(UserError, match="multiple of"):
        make_trials(["HD"], [8], [100.0], 1)


def test_metrics_count_overshoots_and_recovery():
    # start 2, target 5: reach 5 at 1.0 s, overshoot to 6 at 1.2, back to 5 at 1.6,
    # overshoot to 4 at 1.7, final entry at 2.0
    seq = [(0.0, 2), (0.5, 3), (0.8, 4), (1.0, 5), (1.2, 6), (1.6, 5), (1.7, 4), (2.0, 5)]
    m = trial_metrics(seq, 5)
    assert m["overshoots"] == 2
    assert m["completion_time_s"] == pytest.approx(2.0)
    assert m["recovery_time_s"] == pytest.approx(0.8)
    clean = trial_metrics([(0.0, 2), (0.4, 3), (0.9, 4)], 4)
    assert clean == {"completion_time_s": 0.9, "overshoots": 0, "recovery_time_s": None}
    assert trial_metrics([(0.0, 2), (0.4, 3)], 4)["completion_time_s"] is None


def test_each_finished_trial_is_on_disk_before_the_next_starts(tmp_path):
    log = tmp_path / "trials.jsonl"
    trials = make_trials(["HD+VF"], [16], [135.0, 270.0], 2)
    seen = []

    def check(res):
        lines = log.read_text().splitlines()
        seen.append(len(lines))
        assert json.loads(lines[-1])["trial"] == res.trial
        if len(seen) == 3:
            raise RuntimeError("crash")  # the process dies after trial 3

    with pytest.raises(RuntimeError):
        run_task(trials, settings=knob_settings(), log_path=log, on_trial=check, render=False)
    assert seen == [1, 2, 3]
    rows = read_trials(log)
    assert len(rows) == 3
    assert {"completion_time_s", "overshoots", "recovery_time_s", "condition", "sectors"} <= set(
        rows[0]
    )
    # a torn last line (crash mid-write) is skipped, earlier trials survive; appends go on
    with open(log, "a") as f:
        f.write('{"trial": 99, "condi')
    append_json_line(log, {"trial": 100})
    assert [r["trial"] for r in read_trials(log)][-1] == 100
    assert len(read_trials(log)) == 4


def test_sim_finger_completes_trials_and_every_detent_is_timely():
    trials = make_trials(["HD+VF", "VD+CF"], [8, 32], [135.0, 450.0], 1)
    res = run_task(trials, settings=knob_settings(), seed=3)
    assert not any(r.timed_out for r in res)
    for r in res:
        steps = r.target_item - r.start_item
        assert r.crossings >= steps
        assert r.detents == r.crossings
        assert r.max_detent_latency_samples < 64
        assert r.completion_time_s > 0.3


def test_more_sectors_and_longer_distances_take_longer_and_overshoot_more():
    # what the paper found for sector size and distance (its 5.5); condition had no effect
    trials = make_trials(["V"], [8, 32], [135.0, 450.0], 12, seed=4)
    res = run_task(trials, settings=knob_settings(), seed=5, render=False)

    def mean(key, **where):
        vals = [getattr(r, key) for r in res if all(getattr(r, k) == v for k, v in where.items())]
        return float(np.mean([v for v in vals if v is not None]))

    assert mean("completion_time_s", sectors=32) > mean("completion_time_s", sectors=8)
    assert mean("completion_time_s", distance_deg=450.0) > mean(
        "completion_time_s", distance_deg=135.0
    )
    assert mean("overshoots", sectors=32) > mean("overshoots", sectors=8)


def test_a_clumsy_finger_times_out_cleanly():
    tr = make_trials(["HD"], [32], [135.0], 1)[0]
    finger = SimFinger(scatter_frac=3.0, scatter_min_deg=40.0)
    r = run_trial(tr, settings=knob_settings(), finger=finger, max_time_s=2.0, render=False)
    assert r.timed_out and r.completion_time_s is None


def test_live_trial_completes_when_fed_contacts_in_real_time(profile, plugins):
    import threading
    import time

    from console.kernel.client import open_outputs
    from plugins.electrostatic.simulate import min_jerk, rotation_frames
    from plugins.electrostatic.task import run_live_trial

    tr = make_trials(["HD+CF"], [8], [135.0], 1)[0]  # 3 items forward
    box = {}
    done = threading.Event()

    def attach(ses):
        box["ses"] = ses

    def feeder():
        t = np.arange(0, 3.0, 1 / 60)
        ang = min_jerk(t, 0.1, 0.8, 0.0, 135.0)
        frames = rotation_frames(ang, t, noise_mm=0.2, rng=np.random.default_rng(0))
        while "ses" not in box:
            time.sleep(0.001)
        t0 = time.monotonic()
        for tf, cs in frames:
            time.sleep(max(t0 + tf - time.monotonic(), 0))
            ses = box.get("ses")
            if ses is None or done.is_set():
                return
            ses.feed(t0 + tf, cs)

    th = threading.Thread(target=feeder)
    th.start()
    outputs = open_outputs(profile, plugins)  # paced: a live trial runs in real time
    try:
        r = run_live_trial(
            tr, settings=knob_settings(), outputs=outputs, attach=attach, max_time_s=5.0
        )
    finally:
        done.set()
        th.join()
        outputs.close()
    assert not r.timed_out and not r.error and r.finger == "live", r
    assert 0.5 < r.completion_time_s < 1.2  # enters the target item at ~84 % of the move
    assert r.confirm_time_s >= r.completion_time_s + knob_settings()["dwell_s"] - 0.05
    assert r.crossings == 3 and r.detents == 3
    assert box["ses"] is None  # detached when the trial ended


def test_live_task_on_the_twin_camera_runs_and_logs(tmp_path, capsys):
    from console.cli.main import main

    log = tmp_path / "live.jsonl"
    rc = main(["knob", "--input", "live", "--trials", "1", "--max-time", "1.0", "--log", str(log)])
    assert rc == 0
    rows = read_trials(log)
    assert len(rows) == 1 and rows[0]["finger"] == "live"
    assert "turn from item" in capsys.readouterr().out
