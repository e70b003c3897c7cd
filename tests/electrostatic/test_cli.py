"""`haptable knob` and `haptable bench knob` as a user runs them, and the stream through the gate."""

import json
import threading
import time

import numpy as np
import pytest
from scipy.io import wavfile

from console.cli.main import main
from console.core.errors import UserError
from plugins.electrostatic.effects import KnobEffect
from plugins.electrostatic.trial_log import read_trials


def test_knob_task_runs_and_logs_each_trial(tmp_path, capsys):
    log = tmp_path / "knob.jsonl"
    rc = main(
        ["knob", "--sectors", "16", "--condition", "HD+VF", "--trials", "4", "--log", str(log)]
    )
    assert rc == 0
    out = capsys.readouterr().out
    assert "trial   4/4" in out and f"logged 4 trials to {log}" in out
    rows = read_trials(log)
    assert len(rows) == 4 and all(r["condition"] == "HD+VF" and r["sectors"] == 16 for r in rows)
    assert main(["knob", "--trials", "2", "--log", str(log), "--json"]) == 0
    assert len(read_trials(log)) == 6  # appended, never truncated


def test_bad_arguments_are_one_line_errors(tmp_path, capsys):
    assert main(["knob", "--condition", "HD+XY", "--log", str(tmp_path / "x.jsonl")]) == 2
    err = capsys.readouterr().err
    assert "HD+VF" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert main(["knob", "--sectors", "200", "--log", str(tmp_path / "x.jsonl")]) == 2
    assert main(["knob", "--audition", "nope"]) == 2


def test_forces_show_expected_force_and_threshold(capsys):
    assert main(["knob", "--forces", "--condition", "HD+VF", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["signal"] for r in rows] == ["detent", "vf_freq_at_rest_hz", "vf_freq_at_speed_hz"]
    assert all(0 < r["force_mean_n"] < 0.1 and not r["below"] for r in rows)


def test_audition_to_a_wav_file(tmp_path, capsys):
    path = tmp_path / "hdvf.wav"
    assert main(["knob", "--audition", "HD+VF", "--out", str(path)]) == 0
    fs, data = wavfile.read(path)
    assert fs == 48000 and data.shape[1] == 2 and np.all(np.isfinite(data))
    assert np.abs(data[:, 1]).max() > 0.3 and not np.any(data[:, 0])
    assert "16 detents" in capsys.readouterr().out


@pytest.mark.parametrize("condition", ["HD+CF", "VD+VF"])
def test_live_stream_plays_through_the_safety_gate(outputs, profile, condition):
    stream = KnobEffect(profile).stream(condition)
    report = outputs.stream(stream, name="knob")

    def feed():
        for k in range(20):
            stream.post(
                crossings=1 if k % 4 == 0 else 0, velocity_deg_s=10.0 * k, angle_deg=5.0 * k
            )
            time.sleep(0.005)
        stream.request_stop()

    th = threading.Thread(target=feed)
    th.start()
    report.wait(10.0)
    th.join()
    assert report.error == ""
    rec = outputs.recording()
    assert rec is not None and np.abs(rec[:, 1]).max() == pytest.approx(50.0, abs=0.5)
    if condition == "VD+VF":
        assert np.abs(rec[:, 0]).max() > 10.0


def test_effect_render_is_accepted_by_the_gate(outputs, profile, plugins):
    eff = plugins.get("effect", "electrostatic").factory(profile)
    plan = eff.render(vpp=100.0, freq_hz=80.0, duration_s=0.3)
    assert plan.meta["below"] is False and plan.meta["force_mean_n"] > 0
    outputs.play(plan)
    knob_plan = plugins.get("effect", "knob").factory(profile).render(condition="HD+BF")
    outputs.play(knob_plan)


def test_live_session_from_the_effect_drives_its_stream(profile, plugins):
    from plugins.electrostatic.simulate import canned_rotation

    ses = plugins.get("effect", "knob").factory(profile).session("HD", sectors=8)
    for t, cs in canned_rotation():
        ses.feed(t, cs)
        ses.stream.next_block(64)
    assert ses.knob.item == 180 // 45  # +270 then -90 deg from item 0
    assert len(ses.stream.detent_log) == len(ses.crossings) > 0


def test_limits_include_what_the_card_and_amplifier_can_reach(profile):
    from plugins.electrostatic.settings import limits

    lim = limits(profile)
    full, gain = profile.get("audio.full_scale_v"), profile.get("amplifiers.screen_gain")
    assert lim["screen_max_vpp"] == min(profile.get("limits.screen_max_vpp"), 2 * full * gain)
    assert lim["piezo_max_v"] <= full * profile.get("amplifiers.piezo_gain")
    assert limits(None)["screen_max_vpp"] == 200.0


def test_audition_plays_through_the_outputs(capsys):
    # real time on the twin (about 4 s): the path an operator uses
    assert main(["knob", "--audition", "VD+VF", "--sectors", "8"]) == 0
    out = capsys.readouterr().out
    assert "played VD+VF, 8 sectors: 8 sector crossings" in out
    import re

    piezo, screen = map(float, re.search(r"piezo ([\d.]+) V, screen ([\d.]+) V", out).groups())
    assert 30.0 < piezo <= 60.0 and screen == pytest.approx(50.0, abs=0.2)


def test_a_bad_threshold_table_in_the_profile_is_named(tmp_path, capsys):
    from console.config.profile import PROJECT_PROFILES

    prof = tmp_path / "lab.toml"
    prof.write_text(
        (PROJECT_PROFILES / "sim.toml").read_text()
        + "\n[electrostatic]\nthreshold_freq_hz = [50.0, 100.0, 200.0]\nthreshold_vpp = [30.0, 40.0]\nthreshold_square_vpp = [30.0, 40.0, 50.0]\n"
    )
    assert main(["-p", str(prof), "knob", "--forces"]) == 2
    err = capsys.readouterr().err
    assert "threshold_vpp" in err and "2 thresholds for 3 frequencies" in err


def test_bench_knob_quick_with_report(tmp_path, capsys):
    assert main(["bench", "knob", "--quick", "--report", str(tmp_path / "rep")]) == 0
    out = capsys.readouterr().out
    assert "within_one_block: True" in out and "missed: 0" in out and "unconsumed: 0" in out
    md = (tmp_path / "rep" / "knob.md").read_text()
    assert "Crossing to detent" in md and "HD+VF" in md
    assert (tmp_path / "rep" / "knob.png").stat().st_size > 10000


def test_scene_event_matches_the_projector_convention(profile, plugins):
    from plugins.electrostatic.simulate import canned_rotation

    ses = plugins.get("effect", "knob").factory(profile).session("HD", sectors=8)
    for t, cs in canned_rotation():
        ses.feed(t, cs)
    ev = ses.scene_event()
    json.dumps(ev)
    assert ev["type"] == "knob" and ev["item_offset"] == 4
    assert int(ev["angle_deg"] // 45.0) == ev["item_offset"]  # mid-sector: both agree


@pytest.mark.parametrize("waveform", ["sine", "square"])
@pytest.mark.parametrize("freq_hz", [33.0, 247.3, 1000.0])
@pytest.mark.parametrize("duration_s", [0.05, 0.3117])
def test_electrostatic_plans_pass_the_gate_check(profile, plugins, waveform, freq_hz, duration_s):
    from console.safety import Limits, check_plan

    eff = plugins.get("effect", "electrostatic").factory(profile)
    lim = Limits.from_profile(profile)
    if freq_hz * np.pi * 200.0 > lim.slew_v_per_s("screen"):  # 200 Vpp at 1 kHz: too fast
        with pytest.raises(UserError, match="slew limit"):
            eff.render(vpp=200.0, freq_hz=freq_hz, duration_s=duration_s, waveform=waveform)
        return
    plan = eff.render(vpp=200.0, freq_hz=freq_hz, duration_s=duration_s, waveform=waveform)
    check_plan(plan, lim)
    v = plan.segments[0].screen_v
    assert v[0] == 0.0 and v[-1] == 0.0 and np.abs(v).max() == pytest.approx(100.0, rel=0.01)
