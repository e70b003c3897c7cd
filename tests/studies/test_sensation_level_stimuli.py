"""Sensation levels for hand flows (exp2) and the knob (plugins/studies/sensation_stimuli.py):
a ``level = "20 dB SL"`` plan resolved per participant from their thresholds.json, checked
on what the safety gate played on the twin; refusals are one line."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.errors import UserError
from plugins.studies import protocol as P
from plugins.studies import sensation, thresholds
from plugins.studies.runner import Answer, run_plan

EXP2_SL = """
[study]
name = "exp2"
stimulus = "hand_flow"
responses = ["up", "down", "left", "right"]
seed = 3
level = "20 dB SL"
[[regions]]
name = "Rprelim"
center_mm = [371.73, 223.65]
hand = "right"
[[phases]]
name = "main"
factors = { region = ["Rprelim"], direction = ["up"] }
repetitions = 1
"""

KNOB_SL = """
[study]
name = "knob"
stimulus = "knob"
responses = []
seed = 5
level = "20 dB SL"
[[phases]]
name = "main"
factors = { condition = ["V", "HD", "HD+CF", "HD+VF"], sectors = [16], distance_deg = [135] }
repetitions = 1
"""


class Obs:
    """A simulated observer whose detection threshold is ``offset_db`` off the profile's."""

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


def _protocol(tmp_path, text, name):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_hand_flows_play_20_db_above_each_observers_own_threshold(
    tmp_path, map_file, outputs, profile, plugins
):
    from console.files.vibration_map import load_map
    from console.plugin_api import HandFlowGeometry
    from plugins.studies.start import prepare
    from plugins.studies.stimuli import EffectPlayer, play_on

    study = _protocol(tmp_path, EXP2_SL, "exp2-sl.toml")
    vmap = load_map(map_file)
    resolve = sensation.resolver(
        P.load(study), profile, EffectPlayer(plugins, profile, vmap, None).render_base
    )
    per = profile.section("perception")
    out = tmp_path / "out"
    # within 95 V the analytic plate's hand flows reach ~13 dB SL at the population
    # fingertip curve: 20 dB SL needs observers more sensitive than it (12 dB apart)
    played_v = {}
    for pid, offset in (("P01", -22.0), ("P02", -10.0)):
        prep = prepare(study, pid, out, simulate=True, observer=Obs(offset), resolve=resolve)
        assert thresholds.load_curves(out / pid)[0]["procedure"].startswith("simulated")
        before = outputs.recording().shape[0]
        player = EffectPlayer(plugins, profile, vmap, play_on(outputs))
        res = run_plan(prep.files, prep.plan, prep.participant, player=player, responder=Right())
        assert res["finished"]
        rec = outputs.recording()[before:]
        played = _bursts(np.abs(rec).max(axis=1))  # what the gate let through, any channel
        base = [player.render_base(t) for t in prep.plan["trials"]]
        parts = [(b.meta, p) for b in base for p in b.meta["parts"]]
        assert len(played) == len(parts) == 2
        geo = plugins.provider("effect", HandFlowGeometry, profile)
        for i, (v, (meta, part)) in enumerate(zip(played, parts, strict=True)):
            f = part["frequency_hz"]
            q = geo.square_levels_um_per_v(meta["center_mm"], part["actuator"], f, vmap=vmap)
            h = float(q[geo.sides(meta["direction"])[i]].max())  # its strongest active square
            thr = np.interp(np.log(f), np.log(per["freq_hz"]), per["threshold_db_re_1um"])
            thr += per["fingertip_offset_db"] + offset  # the observer's own threshold
            sl = 20 * np.log10(v * h) - thr
            assert sl == pytest.approx(20.0, abs=1.0), (pid, f, sl)
        lv = prep.plan["trials"][0]["stimulus"]["level"]  # the plan records volts, threshold
        assert lv["level"] == "20 dB SL" and len(lv["parts"]) == 2
        assert {"threshold_db", "amplitude_v", "freq_hz", "passive_sl_db"} <= set(lv["parts"][0])
        played_v[pid] = played
    ratio_db = 20 * np.log10(np.array(played_v["P02"]) / np.array(played_v["P01"]))
    assert np.allclose(ratio_db, 12.0, atol=0.1)
    # the population's own threshold: 20 dB SL is beyond the drive limit, refused
    with pytest.raises(
        UserError, match=r"P03: hand flow .* part \d: 20 dB SL .*above the drive"
    ) as e:
        prepare(study, "P03", out, simulate=True, observer=Obs(0.0), resolve=resolve)
    assert "\n" not in str(e.value) and not (out / "P03" / "plan.json").exists()


def _screen(rec: np.ndarray, profile) -> np.ndarray:
    from console.plugin_api import Limits

    return rec[:, Limits.from_profile(profile).channels.index("screen")]


def test_knob_signals_sit_20_db_above_each_observers_electrovibration_threshold(
    tmp_path, outputs, profile, plugins
):
    from console.plugin_api import KnobTrials
    from plugins.studies.sensation_stimuli import knob_profile
    from plugins.studies.start import prepare
    from plugins.studies.stimuli import knob_trial

    study = _protocol(tmp_path, KNOB_SL, "knob-sl.toml")
    resolve = sensation.resolver(P.load(study), profile, lambda trial: None)
    es = profile.section("electrostatic")
    out = tmp_path / "out"
    friction_v = {}
    for pid, offset in (("P01", -18.0), ("P02", -6.0)):  # thresholds 12 dB apart
        prep = prepare(study, pid, out, simulate=True, observer=Obs(offset), resolve=resolve)
        by_cond = {t["condition"]: t for t in prep.plan["trials"]}
        assert by_cond["V"]["stimulus"]["level"]["parts"] == []  # silence stays silence
        for cond in ("HD", "HD+CF", "HD+VF"):
            for part in by_cond[cond]["stimulus"]["level"]["parts"]:
                key = "threshold_square_vpp" if part["waveform"] == "square" else "threshold_vpp"
                f = part["freq_hz"]
                tvpp = np.exp(
                    np.interp(np.log(f), np.log(es["threshold_freq_hz"]), np.log(es[key]))
                )
                thr = 20 * np.log10(tvpp / 2) + offset  # the observer's own, dB re 1 V peak
                sl = 20 * np.log10(part["amplitude_v"]) - thr
                assert sl == pytest.approx(20.0, abs=1.0), (pid, cond, part)
        vf = by_cond["HD+VF"]["stimulus"]["level"]["parts"][1]
        assert vf["freq_range_hz"] == [60.0, 180.0] and vf["freq_hz"] == 180.0  # least felt end
        # what the gate plays: the knob effect with this participant's level
        cf = by_cond["HD+CF"]["stimulus"]["level"]
        eff = plugins.provider("effect", KnobTrials, knob_profile(profile, cf), fresh=True)
        screens = {}
        for cond in ("HD+CF", "HD") if pid == "P01" else ("HD+CF",):  # a render is ~1 s
            before = outputs.recording().shape[0]
            report = outputs.play(eff.render(condition=cond, sectors=16), wait=False)
            report.wait(60)
            assert not report.error
            screens[cond] = np.abs(_screen(outputs.recording()[before:], profile))
        x = screens["HD+CF"]
        per_period = x[: x.size // 267 * 267].reshape(-1, 267).max(axis=1)
        friction = float(np.median(per_period[per_period > 1.0]))  # the friction's sine
        assert friction == pytest.approx(cf["parts"][1]["amplitude_v"], rel=0.02)
        friction_v[pid] = friction
        if "HD" in screens:  # the detent pulses alone
            assert screens["HD"].max() == pytest.approx(cf["parts"][0]["amplitude_v"], rel=0.02)
    # a trial runs the knob with those amplitudes (the simulated finger closes the loop)
    assert not knob_trial(plugins, profile, by_cond["HD+CF"], 1, 0)["error"]
    assert 20 * np.log10(friction_v["P02"] / friction_v["P01"]) == pytest.approx(12.0, abs=0.2)


def test_knob_without_a_curve_or_too_loud_is_one_line(tmp_path, profile):
    from plugins.studies.start import prepare

    study = _protocol(tmp_path, KNOB_SL, "knob-sl.toml")
    resolve = sensation.resolver(P.load(study), profile, lambda trial: None)
    person = dict(age=30, sex="female", handedness="right", hand_width_cm=8.5, hand_length_cm=18.4)
    with pytest.raises(
        UserError,
        match=r"P03 has no electrovibration threshold .*"
        r"study run threshold_electrovibration --participant P03",
    ) as e:
        prepare(study, "P03", tmp_path, details={**person, "consent": True}, resolve=resolve)
    assert "\n" not in str(e.value) and not (tmp_path / "P03" / "plan.json").exists()
    # a vibrotactile curve is no electrovibration curve
    thresholds.save_curve(
        tmp_path / "P05",
        {"modality": "vibrotactile", "waveform": "sine", "point": None,
         "reference": "dB re 1 um", "freq_hz": [100.0, 250.0], "threshold_db": [0.0, -10.0],
         "ci_db": None, "procedure": "test", "protocol_sha256": ""},
    )  # fmt: skip
    with pytest.raises(UserError, match="P05 has no electrovibration threshold"):
        prepare(study, "P05", tmp_path, details={**person, "consent": True}, resolve=resolve)
    # the population threshold: 20 dB SL is ~150 V peak, beyond the screen's 100 V peak
    with pytest.raises(
        UserError, match=r"P04: knob .*: 20 dB SL at .* Hz needs .* V peak .*above .*safety gate"
    ) as e:
        prepare(study, "P04", tmp_path, simulate=True, observer=Obs(0.0), resolve=resolve)
    assert "\n" not in str(e.value) and not (tmp_path / "P04" / "plan.json").exists()
