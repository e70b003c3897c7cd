"""The simulated participant on the plate twin (plugins/twin/plate/observer.py).

Decision layer on known percepts (accuracy vs the lapse rate and chance, binomial
tolerances), the percept on the twin for real flows, and its pieces against second
methods (the drive against ``closed_loop.drive_from_plan``, the tone estimate on a sine
between FFT bins)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from console.core import contracts
from console.core.types import OutputPlan, Segment
from plugins.twin.plate import closed_loop as cl
from plugins.twin.plate import observer as ob
from plugins.twin.plate.model import EXCITATIONS

FS = 8000


def _tone(f_hz: float, n: int, amp: float = 1.0) -> np.ndarray:
    return amp * np.sin(2 * np.pi * f_hz * np.arange(n) / FS)


def _plan(seg_a: Segment, seg_b: Segment) -> OutputPlan:
    return OutputPlan(FS, (seg_a, seg_b), name="test flow", gap_s=0.01)


def _bus(f_hz: float, patches: str, n: int = 4000) -> Segment:
    v = _tone(f_hz, n, 5.0)
    return Segment(v, np.zeros(n), frozenset({patches}))


class FixedPercept(ob.TwinObserver):
    """The observer with a given percept (the decision layer alone)."""

    def __init__(self, percept: ob.Percept) -> None:
        super().__init__(None)
        self.fixed = percept

    def percept(self, trial, played):
        return self.fixed


def _flow_trial(i: int, direction: str = "left_to_right") -> dict:
    return {
        "index": i,
        "direction": direction,
        "stimulus": {"effect": "flow", "left": 51, "right": 52},
    }


def _hand_trial(i: int, direction: str) -> dict:
    return {
        "index": i,
        "direction": direction,
        "stimulus": {"effect": "hand_flow", "center_mm": [300.0, 200.0], "direction": direction},
    }


PLAN = _plan(_bus(250.0, "PA"), _bus(250.0, "PB"))


def _accuracy(obs, trials, seed: int) -> float:
    right = [obs.respond(t, PLAN, participant_seed=seed)[0] == t["direction"] for t in trials]
    return float(np.mean(right))


def _tol(p: float, n: int) -> float:
    return 4 * math.sqrt(p * (1 - p) / n) + 1e-9


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_clear_flow_is_answered_right_one_minus_lapse_of_the_time(seed):
    loud, quiet = np.array([10.0, 0.01]), np.array([0.01, 10.0])
    obs = FixedPercept(ob.Percept("flow", (250.0, 250.0), (loud, quiet), "fingertip"))
    lapse = ob.participant(seed).lapse
    n = 4000
    acc = _accuracy(obs, [_flow_trial(i) for i in range(n)], seed)
    assert abs(acc - (1 - lapse)) < _tol(1 - lapse, n)
    assert acc < 1.0 or lapse < 1e-3  # lapses happen


def test_a_clear_hand_flow_is_answered_right_one_minus_lapse_of_the_time():
    first = np.zeros((3, 3)) + 0.001
    second = first.copy()
    first[:, 0], second[:, -1] = 20.0, 20.0  # a flow to the right
    obs = FixedPercept(ob.Percept("hand_flow", (250.0, 250.0), (first, second), "palm"))
    seed, n = 11, 4000
    lapse = ob.participant(seed).lapse
    acc = _accuracy(obs, [_hand_trial(i, "right") for i in range(n)], seed)
    assert abs(acc - (1 - lapse)) < _tol(1 - lapse, n)
    # and the answers for "left" are then almost all wrong: the observer reads the skin
    assert _accuracy(obs, [_hand_trial(i, "left") for i in range(n)], seed) < 2 * lapse + 0.02


@pytest.mark.parametrize(
    ("kind", "amps", "trial", "chance"),
    [
        ("flow", (np.array([3.0, 3.0]), np.array([3.0, 3.0])), _flow_trial, 0.5),
        ("hand_flow", (np.full((3, 3), 3.0), np.full((3, 3), 3.0)), _hand_trial, 0.25),
    ],
)
def test_a_symmetric_stimulus_is_answered_at_chance(kind, amps, trial, chance):
    obs = FixedPercept(ob.Percept(kind, (250.0, 250.0), amps, "palm"))
    n = 4000
    dirs = ob.FLOW_ANSWERS if kind == "flow" else ob.HAND_ANSWERS
    trials = [trial(i, dirs[i % len(dirs)]) for i in range(n)]
    accs = [_accuracy(obs, trials, seed) for seed in (4, 5)]
    for acc in accs:
        assert abs(acc - chance) < _tol(chance, n)


def test_a_flow_under_threshold_is_not_felt():
    """Both fingers far under threshold: no sensation level, no information."""
    amps = (np.array([1e-4, 1e-7]), np.array([1e-7, 1e-4]))
    obs = FixedPercept(ob.Percept("flow", (250.0, 250.0), amps, "fingertip"))
    _, ev, _ = obs.evidence(_flow_trial(0), PLAN)
    assert np.all(ev == 0)
    n = 3000
    acc = _accuracy(obs, [_flow_trial(i) for i in range(n)], 6)
    assert abs(acc - 0.5) < _tol(0.5, n)


def test_accuracy_grows_with_the_contrast_and_a_jnd_is_about_75_percent():
    """One JND of evidence difference between the two answers: ~75 % before lapses."""
    jnd = float(ob.jnd_db(ob._perception_defaults(), 250.0))
    accs = []
    for contrast_jnd in (0.0, 0.5, 1.0, 3.0):
        # evidence E = contrast; the two answers differ by 2E: one JND apart at E = JND/2
        half = 10 ** (contrast_jnd * jnd / 2 / 20)
        amps = (np.array([2.0 * half, 2.0 / half]), np.array([2.0 / half, 2.0 * half]))
        obs = FixedPercept(ob.Percept("flow", (250.0, 250.0), amps, "fingertip"))
        seed = 21
        p = ob.participant(seed)
        obs_jnd_scale = p.jnd_scale
        n = 6000
        accs.append(_accuracy(obs, [_flow_trial(i) for i in range(n)], seed))
    assert accs == sorted(accs)
    # at one JND apart, corrected for this participant's JND scale and lapse
    from scipy.stats import norm

    expect = norm.cdf(math.sqrt(2) * ob.K_JND / obs_jnd_scale)
    expect = (1 - 2 * p.lapse) * expect + p.lapse
    assert abs(accs[2] - expect) < _tol(expect, 6000)
    assert abs(norm.cdf(math.sqrt(2) * ob.K_JND) - 0.75) < 1e-3


def test_answers_are_reproducible_per_seed_and_differ_between_participants():
    amps = (np.array([3.0, 2.5]), np.array([2.5, 3.0]))
    obs = FixedPercept(ob.Percept("flow", (250.0, 250.0), amps, "fingertip"))
    trials = [_flow_trial(i) for i in range(200)]
    a = [obs.respond(t, PLAN, participant_seed=9) for t in trials]
    b = [obs.respond(t, PLAN, participant_seed=9) for t in trials]
    c = [obs.respond(t, PLAN, participant_seed=10) for t in trials]
    assert a == b
    assert [x[0] for x in a] != [x[0] for x in c]
    assert obs.parameters(9) == obs.parameters(9) != obs.parameters(10)
    assert all(rt > 0.2 for _, rt in a)


def test_response_time_is_longer_for_a_hard_trial():
    clear = (np.array([10.0, 0.01]), np.array([0.01, 10.0]))
    flat = (np.array([3.0, 3.0]), np.array([3.0, 3.0]))
    rts = []
    for amps in (clear, flat):
        obs = FixedPercept(ob.Percept("flow", (250.0, 250.0), amps, "fingertip"))
        rts.append(
            np.median(
                [obs.respond(_flow_trial(i), PLAN, participant_seed=3)[1] for i in range(500)]
            )
        )
    assert rts[1] > rts[0] + 0.3


def test_participant_parameters_follow_the_documented_distributions():
    ps = [ob.participant(s) for s in range(3000)]
    off = np.array([p.threshold_offset_db for p in ps])
    lapse = np.array([p.lapse for p in ps])
    scale = np.log([p.jnd_scale for p in ps])
    assert abs(off.mean()) < 0.3 and abs(off.std() - ob.OFFSET_SD_DB) < 0.3
    a, b = ob.LAPSE_BETA
    assert abs(lapse.mean() - a / (a + b)) < 0.003
    assert abs(scale.std() - ob.JND_SCALE_SIGMA) < 0.02


# --------------------------------------------------------------------- the stimulus pieces
def test_plan_drive_matches_drive_from_plan_for_bus_plans():
    plan = _plan(_bus(200.0, "PA"), _bus(310.0, "PALL"))
    w, spans = ob.plan_drive(plan, guard_s=0.005)
    v_ref, w_ref, spans_ref = cl.drive_from_plan(plan, guard_s=0.005)
    np.testing.assert_allclose(w, v_ref[:, None] * w_ref)
    assert spans == [(s, e) for s, e, _ in spans_ref]


def test_plan_drive_keeps_each_patch_drive():
    n = 2000
    seg = Segment.per_patch({"PA": _tone(100, n), "PC": _tone(100, n, 2.0)})
    w, spans = ob.plan_drive(_plan(seg, seg), guard_s=0.0)
    assert spans[1][0] == spans[0][1] + round(0.01 * FS)
    np.testing.assert_allclose(w[:n, 0], _tone(100, n))
    np.testing.assert_allclose(w[:n, 2], _tone(100, n, 2.0))
    assert not np.any(w[:, 1]) and not np.any(w[:, 3])


@pytest.mark.parametrize("f_hz", [87.3, 250.0, 401.7])
def test_tone_frequency_between_fft_bins(f_hz):
    assert abs(ob.tone_hz(_tone(f_hz, 3001), FS) - f_hz) < 0.05 * FS / 3001
    assert math.isnan(ob.tone_hz(np.zeros(100), FS))


def test_not_a_flow_is_one_line():
    from console.core.errors import UserError

    obs = ob.TwinObserver(None)
    with pytest.raises(UserError, match="flow and hand-flow trials"):
        obs.respond({"index": 0, "stimulus": {"task": "knob"}}, PLAN, participant_seed=1)


# --------------------------------------------------------------------- on the twin
@pytest.fixture(scope="module")
def twin_setup():
    from console.config.plugins import load_plugins
    from console.config.profile import load_profile
    from console.runtime.measured_map import measured_map

    pm = load_plugins()
    prof = load_profile(None, pm)
    return pm, prof, measured_map(prof, pm, None)


def test_the_registered_observer_reads_real_flows_on_the_twin(twin_setup):
    pm, prof, vmap = twin_setup
    obs = pm.provider("observer", contracts.SimulatedObserver, prof)
    assert isinstance(obs, ob.TwinObserver)
    flow = pm.provider("effect", contracts.FlowEffect, prof)
    for d, (a, b) in (("left_to_right", (51, 52)), ("right_to_left", (52, 51))):
        plan = flow.render_flow(a, b, vmap)
        trial = {
            "index": 0,
            "direction": d,
            "stimulus": {"effect": "flow", "from_point": a, "to_point": b, "left": 51, "right": 52},
        }
        answers, ev, jnd = obs.evidence(trial, plan)
        assert answers[int(np.argmax(ev))] == d
        assert ev.max() > 3 * jnd  # the paper's flows are clear (100 % in experiment 1)
        pc = obs.percept(trial, plan)
        # the part's frequency read off the samples is the effect's
        for f, part in zip(pc.freqs_hz, plan.meta["parts"], strict=True):
            assert abs(f - part["frequency_hz"]) < 1.0
        # the active finger's level against the twin's steady FRF at that frequency
        h = obs.twin().frf_um_per_v(
            np.array(plan.meta["from_mm"][:1]),
            np.array(plan.meta["from_mm"][1:]),
            np.array([plan.meta["parts"][0]["frequency_hz"]]),
            EXCITATIONS,
        )
        act = 0 if d == "left_to_right" else 1
        e = EXCITATIONS.index(plan.meta["parts"][0]["actuator"])
        steady = abs(h[e, 0, 0]) * plan.meta["parts"][0]["amplitude_v"]
        assert pc.amplitude_um[0][act] == pytest.approx(steady, rel=0.15)


def test_a_flow_whose_two_parts_are_the_same_is_at_chance_on_the_twin(twin_setup):
    pm, prof, vmap = twin_setup
    obs = pm.provider("observer", contracts.SimulatedObserver, prof)
    flow = pm.provider("effect", contracts.FlowEffect, prof)
    real = flow.render_flow(51, 52, vmap)
    seg = real.segments[0]
    same = OutputPlan(real.sample_rate_hz, (seg, seg), name="same twice", gap_s=real.gap_s)
    trial = _flow_trial(0)
    _, ev, jnd = obs.evidence(trial, same)
    # part 2 starts with part 1's ring-down still there: small, not a direction
    assert abs(ev[0]) < 0.5 * jnd


def test_a_hand_flow_on_the_twin_points_the_way_it_was_rendered(twin_setup):
    """Region R3 of the protocol (placeholder centre): every direction's evidence is
    largest for that direction, and the squares' levels are what the envelopes give."""
    pm, prof, vmap = twin_setup
    obs = pm.provider("observer", contracts.SimulatedObserver, prof)
    hand = pm.provider("effect", contracts.HandFlowEffect, prof)
    for d in ("up", "down", "left", "right"):
        plan = hand.render_hand_flow((560.0, 140.0), d, vmap)
        trial = {
            "index": 0,
            "direction": d,
            "stimulus": {"effect": "hand_flow", "center_mm": [560.0, 140.0], "direction": d},
        }
        answers, ev, jnd = obs.evidence(trial, plan)
        assert answers[int(np.argmax(ev))] == d
        assert ev.max() > jnd
        # opposite answers have opposite evidence (the percept is a direction)
        opp = {"up": "down", "down": "up", "left": "right", "right": "left"}[d]
        assert ev[answers.index(opp)] == pytest.approx(-ev.max())
