"""A participant's thresholds.json (plugins/studies/thresholds.py): round trip, a new
curve replacing the old, log-frequency interpolation, and one line per malformed file."""

from __future__ import annotations

import json
import math

import pytest

from console.core.errors import UserError
from plugins.studies import thresholds as th

CURVE = {
    "modality": "vibrotactile",
    "waveform": "sine",
    "point": None,
    "reference": "dB re 1 um",
    "freq_hz": [250.0, 100.0, 400.0],  # saved ascending
    "threshold_db": [-14.0, 2.0, -9.0],
    "ci_db": [[-15.0, -13.0], [1.0, 3.0], [-10.0, -8.0]],
    "procedure": "staircase 2-down 1-up",
    "protocol_sha256": "ab" * 32,
    "time_utc": "2026-11-29T04:00:00Z",
}


def test_round_trip_replace_and_interpolate(tmp_path):
    folder = tmp_path / "P01"
    path = th.save_curve(folder, CURVE)
    assert path == folder / "thresholds.json"
    ev = {**CURVE, "modality": "electrovibration", "waveform": "square", "reference": "dB re 1 V"}
    th.save_curve(folder, ev)
    th.save_curve(folder, {**CURVE, "threshold_db": [-20.0, -4.0, -15.0]})  # replaces
    curves = th.load_curves(folder)
    assert [c["modality"] for c in curves] == ["electrovibration", "vibrotactile"]
    vt = curves[1]
    assert vt["freq_hz"] == [100.0, 250.0, 400.0] and vt["threshold_db"] == [-4.0, -20.0, -15.0]
    assert vt["ci_db"][0] == [1.0, 3.0]  # moved with its frequency
    assert json.loads(path.read_text())["participant"] == "P01"
    # linear in log frequency: the geometric mean of 100 and 250 Hz is half way
    assert th.threshold_at(curves, "vibrotactile", math.sqrt(100 * 250)) == pytest.approx(-12.0)
    assert th.threshold_at(curves, "vibrotactile", 250.0, waveform="sine") == -20.0
    assert th.threshold_at(curves, "electrovibration", 100.0, "square") == -14.0 + 16.0
    # a quarter octave beyond the range holds the end value, farther is one line
    assert th.threshold_at(curves, "vibrotactile", 400 * 2**0.2) == -15.0
    with pytest.raises(UserError, match="600 Hz is outside the measured 100..400 Hz") as e:
        th.threshold_at(curves, "vibrotactile", 600.0)
    assert "\n" not in str(e.value)
    with pytest.raises(UserError, match="no electrovibration sine threshold curve"):
        th.threshold_at(curves, "electrovibration", 100.0, waveform="sine")
    assert th.load_curves(tmp_path / "P09") == []  # no file: no curves
    # a curve at the skin (dB re 1 um) measured at point 25 serves point 51; volts do not
    at25 = {**vt, "point": "25"}
    assert th.find_curve([at25], "vibrotactile", "sine", "51") is at25
    volts25 = {**at25, "reference": "dB re 1 V"}
    assert th.find_curve([volts25], "vibrotactile", "sine", "51") is None
    assert th.find_curve([volts25, at25], "vibrotactile", "sine", "25") is volts25


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"modality": "thermal"}, r"curves\[0\]: modality is 'thermal', not one of"),
        ({"freq_hz": [100.0, 200.0]}, "threshold_db has 3 values for 2 freq_hz"),
        ({"freq_hz": [100.0, 100.0, 400.0]}, "freq_hz holds a frequency twice"),
        ({"threshold_db": [1.0, "x", 2.0]}, "threshold_db holds 'x', not a finite number"),
        ({"ci_db": [[1.0, 0.0], [1.0, 3.0], [1.0, 2.0]]}, "ci_db holds .* lo <= hi"),
        ({"reference": "dB SPL"}, "reference is 'dB SPL'"),
        ({"procedure": None}, "procedure is None, not a string"),
        ({"freq_hz": [-1.0, 100.0, 400.0]}, "freq_hz must be above 0 Hz"),
    ],
)
def test_malformed_curves_are_one_line_naming_file_and_key(tmp_path, change, match):
    folder = tmp_path / "P02"
    folder.mkdir()
    path = folder / "thresholds.json"
    path.write_text(json.dumps({"participant": "P02", "curves": [{**CURVE, **change}]}))
    with pytest.raises(UserError, match=match) as e:
        th.load_curves(folder)
    msg = str(e.value)
    assert str(path) in msg and "\n" not in msg and "rerun the threshold protocol" in msg
    fix = "new curve: .*; fix the curve given to save_curve"
    with pytest.raises(UserError, match=fix):  # and save_curve refuses it before writing
        th.save_curve(tmp_path / "P03", {**CURVE, **change})
    assert not (tmp_path / "P03" / "thresholds.json").exists()


def test_a_broken_file_is_one_line(tmp_path):
    folder = tmp_path / "P04"
    folder.mkdir()
    (folder / "thresholds.json").write_text('{"curves": {}}')
    with pytest.raises(UserError, match="thresholds.json: curves is missing or not a list"):
        th.load_curves(folder)
    (folder / "thresholds.json").write_text('{"curves": [')
    with pytest.raises(UserError, match="thresholds.json") as e:
        th.load_curves(folder)
    assert "\n" not in str(e.value)
    twice = json.dumps({"curves": [CURVE, CURVE]})
    (folder / "thresholds.json").write_text(twice)
    with pytest.raises(UserError, match=r"curves\[1\]: modality/waveform/point repeats"):
        th.load_curves(folder)
