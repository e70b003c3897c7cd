"""A wrong unit is named as a unit, with its column and what the value takes (a new
operator's try: ``sine(250 hz, 40 v, 0.5 sec)`` and ``sine(250 kV, ...)`` were told
``does not read at column 6: a comma is missing between two parts``)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from console.core.errors import UserError
from console.signals.expr import parse

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize(
    ("typed", "says"),
    [
        ("sine(250 hz, 40 v, 0.5 sec)", "unit 'hz' at column 10 (250 hz): write Hz; "
         "sine's frequency takes Hz or kHz"),
        ("sine(250 kV, 40 V, 0.5 s)", "unit 'kV' at column 10 (250 kV): not a unit of the "
         "signal language; sine's frequency takes Hz or kHz"),
        ("sine(250 Hz, 40 v, 0.5 s)", "unit 'v' at column 17 (40 v): write V; sine's "
         "amplitude takes V, mV, Vpp, % or dB"),
        ("sine(250 Hz, 40 V, 0.5 sec)", "unit 'sec' at column 24 (0.5 sec): write s; "
         "sine's duration takes s, ms or us"),
        ("  chirp(10 Hz, 600 hz, 1 V, 2 s)", "unit 'hz' at column 20"),
        ("sine(250 Hz, 40 V, 1 s) * 50 pct", "unit 'pct' at column 30 (50 pct): write %"),
        ("sine(250 Hz, 40 V, 1 µs)", "unit 'µs' at column 22 (1 µs): write us"),
        ("sine(250 Hz, 1 V, 1 s) * adsr(1 msec, 1 ms, 0.5, 1 ms)", "unit 'msec' at column 33"),
    ],
)  # fmt: skip
def test_a_wrong_unit_is_named_with_its_column_and_what_the_value_takes(typed, says):
    with pytest.raises(UserError) as err:
        parse(typed)
    said = str(err.value)
    assert says in said and "\n" not in said and "comma" not in said, said


def test_a_known_unit_of_another_kind_says_its_column():
    with pytest.raises(UserError) as err:
        parse("sine(250 V, 40 V, 0.5 s)")
    assert "frequency 250 V is a voltage, expected a frequency (in Hz, kHz), column 6" in str(
        err.value
    )


def test_units_stay_what_they_were():
    for typed in (
        "sine(250Hz, 40 V, 0.5 s) * ramp(10 ms)",
        "seq(sine(250 Hz, 40 V, 0.5 s) * adsr(10 ms, 50 ms, 0.7, 100 ms), silence(0.2 s)) * 3",
        "noise(5 V, 1 s, seed=1) * -6 dB",
        "sine(5 Hz, 100 %, 1 s) * sine(250 Hz, 4 V, 1 s)",
    ):
        parse(typed)
    with pytest.raises(UserError, match="a comma is missing"):
        parse("sine(250 Hz 20 V, 1 s)")  # a missing comma is still one


def test_signals_add_names_the_unit_on_the_command_line(tmp_path):
    env = {**os.environ, "HOME": str(tmp_path), "XDG_CONFIG_HOME": str(tmp_path / "cfg")}
    got = subprocess.run(
        [sys.executable, "-m", "console.cli.entry", "signals", "add", "t1",
         "sine(250 kV, 40 V, 0.5 s)"],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=60,
    )  # fmt: skip
    err = got.stderr.strip().splitlines()
    assert got.returncode == 2 and len(err) == 1, got
    assert "unit 'kV' at column 10" in err[0] and "sine's frequency takes Hz or kHz" in err[0]
