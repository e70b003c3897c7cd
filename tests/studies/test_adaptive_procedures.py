"""Adaptive procedures as numbers: staircase rules, convergence, QUEST+ against
``questplus``, the gate's largest level, one-line protocol errors (no Textual, no kernel)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from plugins.studies import adaptive_pf as pf
from plugins.studies.quest import QuestTrack, make_questplus
from plugins.studies.staircase import Staircase, pick_track


def test_scripted_answers_count_reversals_steps_and_stop():
    s = Staircase(down=2, start_db=10, step_db=4, halve_after=2, min_step_db=1)
    s.stop_reversals, s.threshold_reversals = 3, 2
    for a in (True, True, True, True, False, True, True, False):
        assert not s.done
        s.update(a)
    # 10 C, 10 C -> 6; 6 C C -> 2; 2 W: reversal, step 2 -> 4; 4 C C: reversal, step 1 -> 3;
    # 3 W: reversal -> 4, three reversals: stop
    assert s.levels == [10, 10, 6, 6, 2, 4, 4, 3]
    assert s.reversal_levels == [2, 4, 3] and s.reversal_trials == [4, 6, 7]
    assert s.done and s.level_db == 4 and s.threshold_db() == 3.5
    # a wrong first answer moves up but is no reversal; the max_trials stop
    t = Staircase(down=3, start_db=0, step_db=2, halve_after=0, max_trials=4)
    t.replay([False, True, True, True])
    assert t.levels == [0, 2, 2, 2] and t.reversal_levels == [2] and t.level_db == 0
    assert t.done and len(t.answers) == 4


def test_replaying_the_answers_rebuilds_the_same_staircase():
    rng = np.random.default_rng(5)
    answers = list(rng.random(60) < 0.7)
    a = Staircase(down=2, start_db=20, lo_db=0, hi_db=24).replay(answers)
    b = Staircase(down=2, start_db=20, lo_db=0, hi_db=24).replay(answers)
    assert a.levels == b.levels and a.level_db == b.level_db and max(a.levels) <= 24
    names = ["x", "y", "z"]
    assert [pick_track(7, i, names) for i in range(20)] == [
        pick_track(7, i, names) for i in range(20)
    ]
    assert {pick_track(7, i, names) for i in range(60)} == set(names)


def test_step_observer_brackets_its_threshold_on_the_final_grid():
    """A deterministic observer (right exactly when the level >= T): the reversals
    alternate between the two grid levels around T, so the threshold is their midpoint."""
    for down in (2, 3):
        s = Staircase(down=down, start_db=10, step_db=4, halve_after=2, min_step_db=1)
        s.stop_reversals = s.max_trials = 200
        while not s.done:
            s.update(s.level_db >= 3.3)
        assert s.threshold_db() == 3.5  # levels 10, 6, 2, 4, 3: T = 3.3 lies in (3, 4)


@pytest.mark.parametrize("down", [2, 3])
def test_long_staircase_converges_on_levitts_target(down):
    """1-up-2-down visits levels where p(correct) averages 70.7 %, 1-up-3-down 79.4 %
    (Levitt 1971: P(down) = p^n = 1/2); small steps, a smooth 2AFC observer."""
    rng = np.random.default_rng(down)
    t, b, lam = 0.0, 3.0, 0.0
    s = Staircase(down=down, start_db=10, step_db=2, halve_after=2, min_step_db=0.5)
    s.stop_reversals = s.max_trials = 3000
    while not s.done:
        s.update(bool(rng.random() < pf.p_correct(s.level_db, "weibull", t, b, 0.5, lam)))
    visited = np.array(s.levels[200:])
    p_mean = float(np.mean(pf.p_correct(visited, "weibull", t, b, 0.5, lam)))
    assert abs(p_mean - pf.staircase_target(down)) < 0.02
    assert pf.staircase_target(2) == pytest.approx(0.7071, abs=1e-4)
    assert pf.staircase_target(3) == pytest.approx(0.7937, abs=1e-4)


def test_weibull_is_questplus_own_and_level_at_inverts_it():
    # lazy: the reference implementation
    from questplus.psychometric_function import weibull

    x = np.linspace(-20, 20, 9)
    ref = weibull(
        intensity=x, threshold=2.0, slope=3.5, lower_asymptote=0.5, lapse_rate=0.02, scale="dB"
    )
    ours = pf.p_correct(x, "weibull", 2.0, 3.5, 0.5, 0.02)
    assert np.allclose(np.asarray(ref).ravel(), ours, atol=1e-12)
    for fam, t in (("weibull", 2.0), ("logistic", -3.0), ("weibull_linear", 1.5)):
        x70 = pf.level_at(0.707, fam, t, 3.0, 0.5, 0.02)
        assert pf.p_correct(x70, fam, t, 3.0, 0.5, 0.02) == pytest.approx(0.707, abs=1e-12)
    assert pf.p_correct(-3.0, "logistic", -3.0, 3.0, 1 / 3, 0.0) == pytest.approx(2 / 3)


def _grids(family="weibull"):
    return dict(
        family=family,
        task="2afc",
        stim_db=np.arange(-20.0, 21.0, 1.0),
        thresholds_db=np.arange(-20.0, 21.0, 1.0),
        slopes=np.array([2.0, 3.5, 6.0]),
        lapses=np.array([0.0, 0.03]),
    )


def test_quest_update_and_next_level_match_questplus_step_for_step():
    q = QuestTrack(**_grids(), max_trials=8)
    ref = make_questplus("weibull", q.stim_db, q.thresholds_db, q.slopes, q.guess, q.lapses)
    answers = [True, False, True, True, False, True, True, True]
    for a in answers:
        x = q.level_db
        assert x == ref.next_stim["intensity"]
        q.update(x, a)
        ref.update(stim={"intensity": x}, outcome={"response": "correct" if a else "incorrect"})
        post = ref.posterior.transpose("threshold", "slope", "lower_asymptote", "lapse_rate")
        assert np.allclose(q.posterior, post.values, rtol=1e-12, atol=1e-15)
    assert q.done and q.posterior.shape == (41, 3, 1, 2)


@pytest.mark.parametrize(("family", "slope"), [("weibull", 3.5), ("logistic", 6.0)])
def test_quest_recovers_a_known_threshold_in_50_trials(family, slope):
    """A seeded observer of each family (10-90 % over ~7 dB) and its threshold."""
    rng = np.random.default_rng(11)
    t_true, lapse = 3.4, 0.02
    q = QuestTrack(**_grids(family), max_trials=50)
    while not q.done:
        x = q.level_db
        q.update(x, bool(rng.random() < pf.p_correct(x, family, t_true, slope, 0.5, lapse)))
    assert abs(q.threshold_db() - t_true) <= 1.0
    lo, hi = q.ci_db()
    assert lo <= t_true <= hi and hi - lo < 12
    again = QuestTrack(**_grids(family), max_trials=50).replay(
        list(zip(q.levels, q.answers, strict=True))
    )
    assert np.array_equal(again.posterior, q.posterior) and again.level_db == q.level_db


@pytest.fixture(scope="module")
def limits_and_map(tmp_path_factory):
    from console.plugin_api import Limits, load_plugins, load_profile
    from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map

    return Limits.from_profile(load_profile(None, load_plugins())), analytic_map(SSPlate())


@pytest.mark.parametrize(
    "name", ["threshold_vibrotactile", "threshold_electrovibration", "jnd_amplitude"]
)
def test_no_proposed_level_exceeds_what_the_gate_accepts(name, limits_and_map):
    from console.core.errors import SafetyRefusal
    from console.safety.limits import check_plan
    from plugins.studies import adaptive_levels as lv
    from plugins.studies import adaptive_protocol as ap
    from plugins.studies.adaptive_run import (
        State,
        make_setup,
        new_procedure,
        next_trial,
        trial_peaks_v,
        trial_plan,
    )

    limits, vmap = limits_and_map
    proto = ap.load(name)
    setup = make_setup(proto, limits, vmap)
    jnd = proto.procedure["measure"] == "jnd"
    for track, f, _ in proto.tracks[:: max(len(proto.tracks) // 4, 1)]:
        proc = new_procedure(setup, track)
        state = State({track: proc})
        top = setup.max_db[track] - (proto.stimulus["reference_db"] if jnd else 0.0)
        for _ in range(12):  # every answer wrong: the level climbs to the ceiling
            t = next_trial(setup, state, 1)
            assert t["level_db"] <= top + 1e-9
            assert max(trial_peaks_v(setup, t)) <= setup.cap_v[track]
            check_plan(trial_plan(setup, t), limits)  # the gate's own check passes
            if isinstance(proc, QuestTrack):
                proc.update(t["level_db"], False)
            else:
                proc.update(False)
        # the gate's largest level passes and 0.1 dB more is refused: the cap is tight
        unit = setup.units[track]
        check_plan(
            lv.trial_plan(setup.channel, unit, [setup.cap_v[track]], setup.fs, 0, "x"), limits
        )
        over = setup.cap_v[track] * 10 ** (0.1 / 20)
        with pytest.raises(SafetyRefusal):
            check_plan(lv.trial_plan(setup.channel, unit, [over], setup.fs, 0, "x"), limits)
        assert math.isfinite(setup.max_db[track]) and f > 0


def test_a_malformed_protocol_key_is_one_line(tmp_path):
    from console.plugin_api import UserError
    from plugins.studies import adaptive_protocol as ap
    from plugins.studies import protocol as fixed

    good = (ap.protocols.studies_dir() / "threshold_electrovibration.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(good.replace('method = "staircase"', 'methd = "staircase"'))
    with pytest.raises(UserError) as e:
        ap.load(bad)
    msg = str(e.value)
    assert "\n" not in msg and str(bad) in msg and "procedure.method is missing" in msg
    bad.write_text(good.replace("down = 2 ", 'down = "two" '))
    with pytest.raises(UserError, match=r"procedure\.down = 'two': must be an integer"):
        ap.load(bad)
    bad.write_text(good.replace("[observer]", "[observer]\nthreshold = 3"))
    with pytest.raises(UserError, match=r"observer\.threshold is not a protocol key; use one of"):
        ap.load(bad)
    with pytest.raises(UserError, match="an adaptive protocol"):  # the fixed-plan loader
        fixed.load("threshold_electrovibration")


def test_the_simulated_observer_answers_the_levels_played():
    """3AFC: far above its threshold it names the target interval; a silent target is a
    guess among three (1/3); yes/no says yes at its false-alarm rate to silence."""
    from plugins.studies.adaptive_observer import respond

    params = {"family": "weibull", "slope": 4.0, "lapse": 0.0, "false_alarm": 0.1}
    params["tracks"] = {"sine_120Hz": {"threshold_db": 20.0}}
    loud = [
        respond(params, "sine_120Hz", "3afc", [-math.inf, 45.0, -math.inf], 1, (3, i))
        for i in range(200)
    ]
    assert set(loud) == {"2"}
    silent = [respond(params, "sine_120Hz", "3afc", [-math.inf] * 3, 2, (4, i)) for i in range(600)]
    assert abs(silent.count("3") / 600 - 1 / 3) < 0.06 and set(silent) == {"1", "2", "3"}
    yes = [respond(params, "sine_120Hz", "yes_no", [-math.inf], 0, (5, i)) for i in range(600)]
    assert abs(yes.count("yes") / 600 - 0.1) < 0.04
