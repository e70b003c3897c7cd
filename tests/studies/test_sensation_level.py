"""Stimuli at a sensation level (plugins/studies/sensation.py): a ``level = "20 dB SL"``
exp1 plan resolved per participant from their thresholds.json, checked on what the
safety gate played on the twin; refusals are one line."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.errors import UserError
from plugins.studies import protocol as P
from plugins.studies import sensation, thresholds
from plugins.studies.runner import Answer, run_plan

SMALL_EXP1 = """
[study]
name = "exp1"
stimulus = "flow"
responses = ["left_to_right", "right_to_left"]
seed = 4
level = "20 dB SL"
[[pairs]]
name = "F"
left = 51
right = 52
[[phases]]
name = "main"
factors = { pair = ["F"], direction = ["left_to_right", "right_to_left"] }
repetitions = 1
"""


class Obs:
    """A simulated observer whose detection threshold is ``offset_db`` off the curve."""

    def __init__(self, offset_db: float) -> None:
        self.offset_db = offset_db

    def parameters(self, participant_seed: int) -> dict:
        return {"model": "test", "threshold_offset_db": self.offset_db}


class Right:
    def answer(self, trial, played, replays_left, control):
        return Answer(trial["direction"], response_time_s=0.5)


def _bursts(v: np.ndarray) -> list[float]:
    """Peak volts of each stretch of output between silences (a flow's two parts)."""
    from scipy.ndimage import maximum_filter1d

    on = maximum_filter1d(np.abs(v), 97) > 1e-3  # a tone's zero crossings are not silence
    edges = np.flatnonzero(np.diff(on.astype(int))) + 1
    pieces = np.split(np.abs(v), edges)
    return [float(p.max()) for p, o in zip(pieces, np.split(on, edges), strict=True) if o[0]]


@pytest.fixture
def small_exp1(tmp_path):
    p = tmp_path / "exp1-sl.toml"
    p.write_text(SMALL_EXP1)
    return p


def test_each_observer_is_played_20_db_above_their_own_threshold(
    tmp_path, small_exp1, map_file, outputs, profile, plugins
):
    from console.files.vibration_map import load_map
    from plugins.studies.start import prepare
    from plugins.studies.stimuli import EffectPlayer, play_on

    vmap = load_map(map_file)
    proto = P.load(small_exp1)
    resolve = sensation.resolver(
        proto, profile, EffectPlayer(plugins, profile, vmap, None).render_base
    )
    perception = profile.section("perception")
    out = tmp_path / "out"
    sl_played, volts = {}, {}
    for pid, offset in (("P01", -12.0), ("P02", 0.0)):  # thresholds 12 dB apart
        prep = prepare(small_exp1, pid, out, simulate=True, observer=Obs(offset), resolve=resolve)
        curves = thresholds.load_curves(out / pid)  # generated from the observer, saved
        assert curves[0]["procedure"].startswith("simulated")
        before = outputs.recording().shape[0]
        player = EffectPlayer(plugins, profile, vmap, play_on(outputs))
        assert run_plan(prep.files, prep.plan, prep.participant, player=player, responder=Right())[
            "finished"
        ]
        played = _bursts(outputs.recording()[before:, 0])  # what the gate let through
        base = [player.render_base(t) for t in prep.plan["trials"]]
        parts = [p for b in base for p in b.meta["parts"]]
        assert len(played) == len(parts) == 4
        levels = []
        for v, part in zip(played, parts, strict=True):
            f = part["frequency_hz"]
            # the observer's own threshold, from the profile's curve and its offset
            thr = np.interp(
                np.log(f), np.log(perception["freq_hz"]), perception["threshold_db_re_1um"]
            )
            thr += perception["fingertip_offset_db"] + offset
            levels.append(20 * np.log10(v * part["active_um_per_v"]) - thr)
        keys = [(t["direction"], i) for t in prep.plan["trials"] for i in (0, 1)]
        sl_played[pid], volts[pid] = levels, dict(zip(keys, played, strict=True))
        # the plan records the volts and the threshold it used
        rec = prep.plan["trials"][0]["stimulus"]["level"]
        assert rec["level"] == "20 dB SL" and len(rec["parts"]) == 2
        assert {"threshold_db", "amplitude_v", "freq_hz"} <= set(rec["parts"][0])
    for pid, levels in sl_played.items():
        assert np.allclose(levels, 20.0, atol=1.0), (pid, levels)
    # the same parts played 12 dB apart in volts for the two observers
    ratio_db = [20 * np.log10(volts["P02"][k] / volts["P01"][k]) for k in volts["P01"]]
    assert np.allclose(ratio_db, 12.0, atol=0.1)


def test_missing_curve_and_too_loud_are_refused_in_one_line(
    tmp_path, small_exp1, map_file, profile, plugins
):
    from console.files.vibration_map import load_map
    from plugins.studies.start import prepare
    from plugins.studies.stimuli import EffectPlayer

    vmap = load_map(map_file)
    proto = P.load(small_exp1)
    resolve = sensation.resolver(
        proto, profile, EffectPlayer(plugins, profile, vmap, None).render_base
    )
    person = dict(age=30, sex="female", handedness="right", hand_width_cm=8.5, hand_length_cm=18.4)
    with pytest.raises(
        UserError,
        match=r"P03 has no vibrotactile threshold .*threshold_vibrotactile --participant P03",
    ) as e:
        prepare(small_exp1, "P03", tmp_path, details={**person, "consent": True}, resolve=resolve)
    assert "\n" not in str(e.value)
    assert not (tmp_path / "P03" / "plan.json").exists()
    # an observer 8 dB less sensitive: 20 dB SL needs more than the drive limit
    with pytest.raises(
        UserError,
        match=r"P04: flow .* part \d: 20 dB SL at .* Hz needs .* V .*above the drive limit",
    ) as e:
        prepare(small_exp1, "P04", tmp_path, simulate=True, observer=Obs(8.0), resolve=resolve)
    assert "\n" not in str(e.value)
    # without a resolver a level is refused, never played at another
    with pytest.raises(UserError, match="study.level = '20 dB SL': run it with"):
        prepare(small_exp1, "P05", tmp_path, simulate=True, observer=Obs(0.0))


@pytest.mark.parametrize(
    ("text", "stim", "match"),
    [
        ("20 dB", "flow", "give a sensation level"),
        ("0 V", "flow", "give volts above 0"),
        ("90 dB SL", "flow", "-20 .. 60 dB SL"),
        ("20 dB SL", "tone", "only flow, hand_flow and knob studies"),
    ],
)
def test_bad_levels_are_one_line(text, stim, match):
    with pytest.raises(UserError, match=match) as e:
        sensation.parse_level(text, "exp1.toml", stim)
    assert "study.level" in str(e.value) and "\n" not in str(e.value)
    assert sensation.parse_level("1.5 V", "x", "flow") == sensation.Level("volts", 1.5, "1.5 V")
