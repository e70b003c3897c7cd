"""Malformed AHAP and ``.haptic`` files through ``haptable signals import`` (issue 31).

Every case runs the real command in-process and must end with ONE line on stderr
(``haptable: error: ...``, exit 2) naming the file, the key or value, and the fix; nothing
is saved to the library. The files are written here from the public format descriptions;
the last two ``.haptic`` cases are the invalid files of facebook/meta-haptics-sdk
(``core/haptic_data/test_files/invalid_single_amplitude_breakpoint.haptic`` and
``invalid_freq_bp_outside_amp_env.haptic``), which Meta's own reader refuses too.
"""

from __future__ import annotations

import json

import pytest

from console.cli.main import main


def _ev(t=0.0, kind="HapticContinuous", dur=0.2, intensity=0.5) -> dict:
    ev = {"Time": t, "EventType": kind, "EventDuration": dur,
          "EventParameters": [{"ParameterID": "HapticIntensity", "ParameterValue": intensity}]}  # fmt: skip
    return {"Event": ev}


def _ahap(pattern=None, **top) -> str:
    return json.dumps({"Version": 1.0, "Pattern": pattern or [_ev()], **top})


def _haptic(amp=None, major=1) -> str:
    env = {"amplitude": amp if amp is not None else [{"time": 0, "amplitude": 0.5},
                                                     {"time": 0.2, "amplitude": 0}]}  # fmt: skip
    return json.dumps({"version": {"major": major, "minor": 0, "patch": 0},
                       "signals": {"continuous": {"envelopes": env}}})  # fmt: skip


CURVE = {"ParameterCurve": {"ParameterID": "HapticIntensityControl", "Time": 0.0,
         "ParameterCurveControlPoints": [{"Time": 0.1, "ParameterValue": 1},
                                         {"Time": 0.05, "ParameterValue": 0.5}]}}  # fmt: skip

# (id, file name, text, words the line must hold)
CASES = [
    ("bad-json", "a.ahap", '{"Version": 1.0,\n "Pattern": [\n  {"Event": }\n]}', ("a.ahap", "line 3")),
    ("no-pattern", "a.ahap", '{"Version": 1.0}', ("a.ahap", "Pattern", "missing")),
    ("negative-time", "a.ahap", _ahap([_ev(t=-0.5)]), ("Pattern[0].Event.Time", "-0.5", "0..")),
    ("intensity-1.7", "a.ahap", _ahap([_ev(intensity=1.7)]),
     ("EventParameters[0]", "HapticIntensity", "1.7", "from 0 to 1")),
    ("unknown-event-type", "a.ahap", _ahap([_ev(kind="HapticBuzz")]),
     ("EventType", "HapticBuzz", "HapticContinuous")),
    ("wrong-version", "a.ahap", _ahap(Version=2.0), ("a.ahap", "Version", "1.0")),
    ("pattern-not-list", "a.ahap", '{"Version": 1, "Pattern": {}}', ("Pattern", "a list")),
    ("no-duration", "a.ahap", _ahap([{"Event": {"Time": 0, "EventType": "HapticContinuous"}}]),
     ("EventDuration", "missing")),
    ("curve-out-of-order", "a.ahap", _ahap([_ev(), CURVE]), ("ControlPoints[1].Time", "order")),
    ("nan-value", "a.ahap", _ahap([_ev(intensity=float("nan"))]), ("ParameterValue", "nan", "from 0 to 1")),
    ("only-audio", "a.ahap", _ahap([_ev(kind="AudioCustom")]), ("Pattern", "no haptic event")),
    ("haptic-wrong-version", "b.haptic", _haptic(major=2), ("b.haptic", "version.major", "2")),
    ("haptic-no-amplitude", "b.haptic", _haptic(amp=[]), ("envelopes.amplitude", "empty")),
    ("haptic-amplitude-1.5", "b.haptic", _haptic(amp=[{"time": 0, "amplitude": 1.5}]),
     ("amplitude[0].amplitude", "1.5")),
    ("haptic-time-backwards", "b.haptic",
     _haptic(amp=[{"time": 0.2, "amplitude": 0.5}, {"time": 0.1, "amplitude": 0}]),
     ("amplitude[1].time", "order")),
    ("haptic-no-signals", "b.haptic", '{"version": {"major": 1}}', ("signals", "missing")),
    ("haptic-one-breakpoint", "b.haptic", _haptic(amp=[{"time": 0, "amplitude": 0.2}]),
     ("envelopes.amplitude", "one breakpoint", "at least two")),
    ("haptic-freq-after-the-end", "b.haptic", json.dumps({"version": {"major": 1}, "signals": {
        "continuous": {"envelopes": {
            "amplitude": [{"time": 0, "amplitude": 1}, {"time": 1, "amplitude": 1}],
            "frequency": [{"time": 0, "frequency": 1}, {"time": 1, "frequency": 1},
                          {"time": 1.0001, "frequency": 0}]}}}}),
     ("frequency[2].time", "1.0001", "amplitude envelope's end")),
    ("unknown-suffix", "c.json", _ahap(), ("c.json", "--format")),
]  # fmt: skip


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_malformed_haptic_file_one_line(case, tmp_path, capsys):
    _id, name, text, words = case
    f = tmp_path / name
    f.write_text(text, encoding="utf-8")
    capsys.readouterr()
    rc = main(["signals", "import", str(f), "--name", "x"])
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert rc == 2, f"exit {rc}: {err!r}"
    assert len(lines) == 1, err
    assert lines[0].startswith("haptable: error: ")
    for w in words:
        assert w in lines[0], f"{w!r} not in {lines[0]!r}"
    assert main(["signals", "show", "x"]) == 2  # nothing saved


def test_level_above_the_gate_refused(tmp_path, capsys):
    f = tmp_path / "ok.ahap"
    f.write_text(_ahap(), encoding="utf-8")
    capsys.readouterr()
    assert main(["signals", "import", str(f), "--level", "300 V"]) == 2
    line = capsys.readouterr().err.strip()
    assert "--level" in line and "300" in line and "at most 100 V" in line
