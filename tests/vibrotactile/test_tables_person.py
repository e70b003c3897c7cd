"""Perceptual tables for one person (plugins/vibrotactile/person_thresholds.py): a
participant's thresholds.json (as the studies write it) in place of the population
curve; the rule's levels move by the person's offset, and so may the entries."""

from __future__ import annotations

import argparse

import numpy as np
import pytest

from console.core.errors import UserError
from console.files.vibration_map import make_map, save_map
from plugins.studies import thresholds as th
from plugins.vibrotactile.perceptual_rule import PerceptualRule, felt_db
from plugins.vibrotactile.person_thresholds import personal_rule
from plugins.vibrotactile.tables import build_tables, load_tables, query_indices
from plugins.vibrotactile.thresholds import Perception

RULE = PerceptualRule(Perception(), drive_v=10.0, target_sl_db=20.0)
FREQ = [10.0, 100.0, 250.0]
# one excitation, two points: active / passive um/V per bin (test_perceptual_tables.py)
MAP = make_map(
    np.array([[[100.0, 1.0, 0.1], [10.0, 0.2, 0.05]]], dtype=complex),
    np.array(FREQ),
    np.array([1, 2]),
    np.array([[0.0, 0.0], [60.0, 0.0]]),
    ("PA",),
    None,
    require_all=False,
)


def _person(folder, offset_db, freq=FREQ, reference="dB re 1 um"):
    """A participant's thresholds.json: the population fingertip curve + ``offset_db``."""
    thr = Perception().threshold_db(np.array(freq), "fingertip") + offset_db
    curve = {
        "modality": "vibrotactile", "waveform": "sine", "point": None, "reference": reference,
        "freq_hz": list(freq), "threshold_db": [float(t) for t in thr], "ci_db": None,
        "procedure": "test", "protocol_sha256": "",
    }  # fmt: skip
    return th.save_curve(folder, curve)


def test_a_less_sensitive_persons_tables_move_by_their_offset(tmp_path):
    path = _person(tmp_path / "P01", +12.0)  # 12 dB less sensitive than the population
    rule = personal_rule(RULE, path, np.array(FREQ))
    off_pop, _ = RULE.levels(np.array(FREQ))
    off_p01, _ = rule.levels(np.array(FREQ))
    assert off_p01 - off_pop == pytest.approx([-12.0] * 3)  # levels above P01's threshold
    # 100 Hz at full drive: 18 dB above the population's threshold, 6 dB above P01's; the
    # felt difference is then the contrast (14 dB) for the population, 6 dB for P01
    assert off_pop[1] == pytest.approx(18.0) and off_p01[1] == pytest.approx(6.0)
    assert felt_db(RULE, 100.0, 1.0, 0.2)[0] == pytest.approx(20 * np.log10(5))
    assert felt_db(rule, 100.0, 1.0, 0.2)[0] == pytest.approx(6.0)
    pop, p01 = build_tables(MAP, 650.0, perceptual=RULE), build_tables(MAP, 650.0, perceptual=rule)
    assert query_indices(pop, 0, 1)["frequency_hz"] == 100.0
    # for P01 100 Hz is barely felt: the entry moves to 10 Hz (30 dB above their threshold)
    assert query_indices(p01, 0, 1)["frequency_hz"] == 10.0


def test_the_tables_command_takes_a_persons_thresholds(tmp_path, ctx, capsys):
    from plugins.vibrotactile.cli.tables import configure_tables, run_tables

    path = _person(tmp_path / "P02", -12.0)
    save_map(tmp_path / "two.npz", MAP)
    parser = argparse.ArgumentParser()
    configure_tables(parser)
    out = tmp_path / "p02.npz"
    args = parser.parse_args(
        ["build", str(tmp_path / "two.npz"), "--out", str(out), "--allow-missing",
         "--thresholds", str(path)]
    )  # fmt: skip
    assert run_tables(args, ctx) == 0
    assert f"thresholds of {path}" in capsys.readouterr().out
    stored = load_tables(out).perceptual.perception  # the file keeps P02's curve
    pop = Perception().threshold_db(np.array(FREQ), "fingertip")
    assert stored.threshold_db(np.array(FREQ), "fingertip") == pytest.approx(pop - 12.0)


def test_a_curve_short_of_the_band_or_in_volts_is_one_line(tmp_path):
    short = _person(tmp_path / "P03", 0.0, freq=[40.0, 100.0, 250.0])
    with pytest.raises(
        UserError,
        match=r"P03's vibrotactile threshold covers 40..250 Hz .* 10..250 Hz.*"
        r"play_band_hz = \[40, 250\]",
    ) as e:
        personal_rule(RULE, short, np.array(FREQ))
    assert str(short) in str(e.value) and "\n" not in str(e.value)
    volts = _person(tmp_path / "P04", 0.0, reference="dB re 1 V")
    with pytest.raises(UserError, match="P04 has no vibrotactile threshold in dB re 1 um.*"
                       "threshold_vibrotactile --participant P04") as e:  # fmt: skip
        personal_rule(RULE, volts, np.array(FREQ))
    assert "\n" not in str(e.value)
