"""The runner: durable events, replays within the rules, abort and resume, questionnaire,
stimuli through the effects and the outputs' safety gate."""

from __future__ import annotations

import json
import threading

import pytest

from console.core.errors import UserError
from console.files.atomic import append_json_line
from plugins.studies import protocol as P
from plugins.studies.plan import make_plan
from plugins.studies.runner import Answer, Control, run_plan
from plugins.studies.store import (
    make_participant,
    open_run,
    progress,
    read_events,
    write_json_atomic,
)

PERSON = dict(
    age=30, sex="female", handedness="right", hand_width_cm=8.5, hand_length_cm=18.4, consent=True
)


class FakePlayer:
    def __init__(self):
        self.played = []

    def play(self, trial, attempt):
        self.played.append((trial["index"], attempt))
        return {"trial": trial["index"], "attempt": attempt}


class Scripted:
    """Answers from a list: "replay" or a response; ``hook(trial)`` runs first."""

    def __init__(self, script, hook=None):
        self.script = list(script)
        self.hook = hook

    def answer(self, trial, played, replays_left, control):
        if self.hook:
            self.hook(trial, control)
        control.check()
        a = self.script.pop(0) if self.script else trial["direction"]
        return Answer(replay=True) if a == "replay" else Answer(response=a, response_time_s=0.4)

    def rate(self, item, q, records, control):
        return 5


def _events(files, kind):
    return [e for e in files.events() if e["event"] == kind]


def test_events_are_durable_lines_and_a_torn_line_is_skipped(tmp_path):
    path = tmp_path / "t.jsonl"
    append_json_line(path, {"event": "start", "trial": 0})
    with open(path, "ab") as f:
        f.write(b'{"event": "done", "tri')  # a crash mid-write
    append_json_line(path, {"event": "done", "trial": 0})
    assert [e["event"] for e in read_events(path)] == ["start", "done"]
    write_json_atomic(tmp_path / "p.json", {"a": 1})
    assert json.loads((tmp_path / "p.json").read_text()) == {"a": 1}
    assert not list(tmp_path.glob(".*.tmp"))


def test_participants_are_checked_with_one_line_each():
    p = make_participant("P01", **PERSON)
    assert p.consent_noted and p.consent_time.endswith("Z")
    for key, bad, msg in [
        ("age", 300, "--age 300: give a number from 1 to 120"),
        ("sex", "x", "--sex x: use one of female"),
        ("handedness", "both", "--handedness both: use one of left"),
        ("hand_width_cm", "wide", "--hand-width-cm wide: give a number"),
        (
            "consent",
            None,
            r"consent not noted; note the participant's informed consent \(--consent\)",
        ),
    ]:
        with pytest.raises(UserError, match=msg):
            make_participant("P01", **{**PERSON, key: bad})
    with pytest.raises(UserError, match="participant 'a/b'"):
        make_participant("a/b", **PERSON)


def test_sex_and_handedness_in_any_case_or_by_their_start():
    for given, sex in (("F", "female"), ("Female", "female"), ("m", "male"), ("U", "undisclosed")):
        assert make_participant("P01", **{**PERSON, "sex": given}).sex == sex
    assert make_participant("P01", **{**PERSON, "handedness": "L"}).handedness == "left"
    assert make_participant("P01", **{**PERSON, "handedness": " Ambi "}).handedness == (
        "ambidextrous"
    )
    with pytest.raises(UserError, match="--sex x: use one of female, male, other, undisclosed"):
        make_participant("P01", **{**PERSON, "sex": "x"})


def test_the_screen_hears_every_missing_field_at_once_in_its_own_words(tmp_path, small_exp2):
    """The Studies screen's refusals name its fields ("folder", "consent noted",
    "simulated"), every missing one at once; the CLI's name its flags."""
    from plugins.studies.start import prepare
    from plugins.studies.words import SCREEN

    empty = dict.fromkeys(PERSON)
    with pytest.raises(UserError) as err:
        make_participant("P01", **empty, words=SCREEN)
    assert str(err.value) == (
        "participant P01: age, sex, handedness, hand width cm and hand length cm missing; "
        "give them and note the consent (tick 'consent noted') before the first trial"
    )
    with pytest.raises(UserError) as err:
        make_participant("P01", **{**PERSON, "hand_width_cm": "wide"}, words=SCREEN)
    assert "hand width cm = 'wide': give a number from 3 to 30" in str(err.value)
    with pytest.raises(UserError, match=r"\(tick 'consent noted'\) before the first trial"):
        make_participant("P01", **{**PERSON, "consent": None}, words=SCREEN)
    with pytest.raises(UserError, match="--age and --sex missing; give them before"):
        make_participant("P01", **{**PERSON, "age": None, "sex": ""})
    # a folder that cannot be made, a participant stored as simulated
    (tmp_path / "file").write_text("")
    with pytest.raises(UserError) as err:
        prepare(str(small_exp2), "P01", tmp_path / "file", details=PERSON, words=SCREEN)
    assert str(err.value).endswith("give a writable folder") and "--" not in str(err.value)
    prepare(str(small_exp2), "P01", tmp_path / "runs", simulate=True)
    with pytest.raises(UserError) as err:
        prepare(str(small_exp2), "P01", tmp_path / "runs", details=PERSON, words=SCREEN)
    assert str(err.value).endswith(
        "participant P01 is simulated; tick 'simulated' to resume it, or use another folder"
    )
    with pytest.raises(UserError, match="resume it with --simulate, or use another --out"):
        prepare(str(small_exp2), "P01", tmp_path / "runs", details=PERSON)


def test_a_run_writes_plan_first_then_start_and_done_with_the_columns(tmp_path, small_exp2):
    plan = make_plan(P.load(small_exp2), "P01")
    files, plan = open_run(tmp_path, "P01", plan)
    assert json.loads(files.plan_path.read_text())["trials"] == plan["trials"]
    assert not files.trials_path.exists()  # the plan is stored before the first trial
    player = FakePlayer()
    # trial 0 (unlimited replays): two replays; trial 2 (one replay): a second is refused
    script = ["replay", "replay", "up", "right", "replay", "replay", "left"]
    seen = []
    res = run_plan(
        files,
        plan,
        {"id": "P01"},
        player=player,
        responder=Scripted(script),
        notify=lambda k, i: seen.append(k),
    )
    assert res["finished"] and res["done"] == 6 == res["total"]
    done = _events(files, "done")
    assert [d["trial"] for d in done] == list(range(6))
    assert [d["replays"] for d in done][:3] == [2, 0, 1]
    assert player.played[:4] == [(0, 0), (0, 1), (0, 2), (1, 0)]
    assert "refused" in seen
    cols = {
        "participant",
        "experiment",
        "phase",
        "trial",
        "pair",
        "region",
        "direction",
        "condition",
        "stimulus",
        "response",
        "correct",
        "replays",
        "response_time_s",
        "t_start",
        "t_end",
    }
    for d in done:
        assert cols <= set(d)
        assert d["correct"] == (d["response"] == d["direction"])
        assert d["t_end"] >= d["t_start"]
    assert done[0]["response"] == "up" and done[2]["response"] == "left"
    starts = _events(files, "start")
    assert [s["trial"] for s in starts] == list(range(6))


def test_abort_mid_trial_marks_it_interrupted_and_resume_repeats_it(tmp_path, small_exp2):
    plan = make_plan(P.load(small_exp2), "P01")
    files, plan = open_run(tmp_path, "P01", plan)
    control = Control()

    def hook(trial, control):
        if trial["index"] == 3:
            control.abort("stop now")

    res = run_plan(
        files,
        plan,
        {"id": "P01"},
        player=FakePlayer(),
        responder=Scripted([], hook),
        control=control,
    )
    assert res["aborted"] and res["done"] == 3 and not res["finished"]
    assert _events(files, "interrupted")[-1]["trial"] == 3
    # resume: the stored plan, at trial 3 again
    files2, plan2 = open_run(tmp_path, "P01", make_plan(P.load(small_exp2), "P01"))
    player = FakePlayer()
    res = run_plan(files2, plan2, {"id": "P01"}, player=player, responder=Scripted([]))
    assert res["finished"] and player.played[0] == (3, 0)
    done = _events(files2, "done")
    assert sorted(d["trial"] for d in done) == list(range(6))


def test_pause_holds_between_trials(tmp_path, small_exp2):
    plan = make_plan(P.load(small_exp2), "P01")
    files, plan = open_run(tmp_path, "P01", plan)
    control = Control()
    control.pause()
    seen = []
    t = threading.Thread(
        target=run_plan,
        args=(files, plan, {"id": "P01"}),
        kwargs=dict(
            player=FakePlayer(),
            responder=Scripted([]),
            control=control,
            notify=lambda k, i: seen.append(k),
        ),
    )
    t.start()
    for _ in range(100):
        if "paused" in seen:
            break
        threading.Event().wait(0.02)
    assert "paused" in seen and not files.trials_path.exists()
    control.resume()
    t.join(10)
    assert progress(plan, files.events()).next_trial is None


def test_an_unwritable_folder_is_one_line(tmp_path, small_exp2):
    (tmp_path / "file").write_text("")
    with pytest.raises(UserError, match="cannot make the participant's folder .* writable --out"):
        open_run(tmp_path / "file", "P01", make_plan(P.load(small_exp2), "P01"))


def test_a_changed_protocol_does_not_resume_an_old_plan(tmp_path, small_exp2):
    open_run(tmp_path, "P01", make_plan(P.load(small_exp2), "P01"))
    small_exp2.write_text(
        small_exp2.read_text().replace("repetitions = 1\nblock_by", "repetitions = 2\nblock_by")
    )
    with pytest.raises(
        UserError, match="protocol_sha256 .* resume with the same protocol file or use a new --out"
    ):
        open_run(tmp_path, "P01", make_plan(P.load(small_exp2), "P01"))


def test_knob_questionnaire_follows_each_condition_and_resumes_per_item(tmp_path):
    text = P.find("knob").read_text().replace("repetitions = 6", "repetitions = 1")
    text = text.replace("sectors = [8, 16, 32]", "sectors = [8]").replace(
        "[135, 270, 450]", "[135]"
    )
    path = tmp_path / "knob-small.toml"
    path.write_text(text)
    plan = make_plan(P.load(path), "P02")
    files, plan = open_run(tmp_path, "P02", plan)

    class Knob:
        def play(self, trial, attempt):
            return {
                "completion_time_s": 1.0,
                "overshoots": 1,
                "recovery_time_s": 0.3,
                "timed_out": False,
                "error": "",
                "detents": 3,
            }

    control = Control()
    rated = []

    class R(Scripted):
        def rate(self, item, q, records, control):
            rated.append((q["condition"], item["category"], item["item"]))
            assert [r["condition"] for r in records] == [q["condition"]]
            if len(rated) == 20:
                control.abort("break")
            return 1 + len(rated) % 7

    res = run_plan(files, plan, {"id": "P02"}, player=Knob(), responder=R([]), control=control)
    assert res["aborted"] and res["done"] == 2  # trial 0, 14 items, trial 1, 6 items
    res = run_plan(files, plan, {"id": "P02"}, player=Knob(), responder=R([]))
    assert res["finished"] and res["done"] == 4
    qs = _events(files, "questionnaire")
    assert len(qs) == 4 * 14 and len({(q["condition"], q["category"], q["item"]) for q in qs}) == 56
    assert all(1 <= q["score"] <= 7 for q in qs)
    order = [e["event"] for e in files.events()]
    assert order[:3] == ["start", "done", "questionnaire"]
    done = _events(files, "done")
    assert {"completion_time_s", "overshoots", "recovery_time_s", "sectors", "distance_deg"} <= set(
        done[0]
    )


def test_stimuli_are_played_through_the_effects_and_the_gate(
    tmp_path, small_exp2, map_file, outputs, profile, plugins
):
    from console.files.vibration_map import load_map
    from plugins.studies.stimuli import EffectPlayer, check_places, play_on

    vmap = load_map(map_file)
    plan = make_plan(P.load(small_exp2), "P01")
    check_places(plan, vmap)
    files, plan = open_run(tmp_path, "P01", plan)
    player = EffectPlayer(plugins, profile, vmap, play_on(outputs))
    got = []

    class Check(Scripted):
        def answer(self, trial, played, replays_left, control):
            got.append(played)
            return super().answer(trial, played, replays_left, control)

    res = run_plan(files, plan, {"id": "P01"}, player=player, responder=Check(["replay"]))
    assert res["finished"]
    assert got[0] is got[1]  # a replay plays the same plan
    assert [p.name for p in got[2:]] == [p.name for p in map(player.prepare, plan["trials"][1:])]
    rec = outputs.recording()  # what the twin's amplifiers received
    n_played = sum(round(p.duration_s * p.sample_rate_hz) for p in got)
    assert rec.shape[0] >= n_played and abs(rec[:, 0]).max() > 1.0
    # the gate refuses (e-stop): the trial is marked interrupted, the run stops in one line
    files2, plan2 = open_run(tmp_path, "P02", make_plan(P.load(small_exp2), "P02"))
    outputs.estop("test")
    with pytest.raises(UserError, match="trial 1: .*e-stop") as e:
        run_plan(files2, plan2, {"id": "P02"}, player=player, responder=Scripted([]))
    assert "\n" not in str(e.value)
    assert [x["event"] for x in files2.events()] == ["start", "interrupted"]


def test_places_off_the_map_are_one_line(tmp_path, small_exp2, map_file):
    from console.files.vibration_map import load_map
    from plugins.studies.stimuli import check_places

    bad = small_exp2.read_text().replace("[580.0, 320.0]", "[5800.0, 320.0]")
    small_exp2.write_text(bad)
    with pytest.raises(
        UserError, match=r"region R4: centre \(5800, 320\) mm is outside the map's grid"
    ):
        check_places(make_plan(P.load(small_exp2), "P01"), load_map(map_file))
    text = P.find("exp1").read_text().replace("left = 33\nright = 22", "left = 22\nright = 33")
    p = tmp_path / "exp1.toml"
    p.write_text(text)
    with pytest.raises(UserError, match="pair 4: left point 22 .* is not left of right point 33"):
        check_places(make_plan(P.load(p), "P01"), load_map(map_file))


def test_a_live_knob_trial_streams_through_the_gate_while_contacts_turn_it(
    outputs, profile, plugins
):
    """A person's knob trial (``LiveKnob``): the camera's contacts (here a two-finger
    rotation as the camera loop would deliver it) turn the knob to the target; the trial
    ends there with its measures, and its feedback went through the gate."""
    import time
    from types import SimpleNamespace

    import numpy as np

    from plugins.electrostatic.simulate import min_jerk, rotation_frames
    from plugins.studies.stimuli import LiveKnob

    live = LiveKnob(plugins, profile, outputs)
    trial = {
        "index": 0,
        "stimulus": {"task": "knob", "condition": "HD+CF", "sectors": 8, "distance_deg": 135.0},
    }
    got = {}
    t = threading.Thread(target=lambda: got.update(live.play(trial)))
    t.start()
    t0 = time.monotonic()
    while t.is_alive() and time.monotonic() - t0 < 10:
        s = time.monotonic() - t0
        angle = float(min_jerk(np.array([s]), 0.3, 1.2, 0.0, 135.0)[0])
        ((_, contacts),) = rotation_frames(np.array([angle]), np.array([s]))
        live.frame(SimpleNamespace(t_capture_s=time.monotonic()), {"contacts": contacts})
        time.sleep(1 / 60)
    t.join(10)
    assert not got["timed_out"] and got["error"] == ""
    assert got["target_item"] - got["start_item"] == 3
    assert 1.0 < got["completion_time_s"] < 5.0
    assert got["detents"] >= 3 and live.frames > 60
    rec = outputs.recording()
    assert abs(rec[:, 1]).max() > 10.0  # HD+CF: friction and detents on the screen channel
