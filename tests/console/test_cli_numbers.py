"""Numbers on the command line: every one declared with its range in one place
(``console.core.options``), every bad one refused before the command runs as ONE line
``haptable: error: <command> <option>: <value> ...; give ...``, exit 2: never a
traceback, an internal error, a silent default or a run that never ends.

The cases run the real ``haptable`` in-process. ``CASES`` is importable: with
``$HAPTABLE_MALFORMED_TALLY`` set each outcome is appended there (the before/after
counts of issue 25's closing note; tests/malformed/tally.py runs them as processes).
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import pytest

from console.cli.main import build_parser, main
from console.core.options import (
    MAX_SEED,
    Number,
    finite_float,
    from_field,
    integer,
    port,
    seconds,
    usage_line,
)
from console.core.schema import Field

F_HZ = [float(f) for f in range(0, 651, 25)]


@dataclass(frozen=True)
class Case:
    id: str
    argv: Callable[[Path, dict], list[str]]
    words: tuple[str, ...]
    source: str = "own"  # "issue": listed in issue 25


def _c(id_: str, argv: list[str] | Callable, *words: str, source: str = "own") -> Case:
    make = argv if callable(argv) else (lambda d, fx, a=argv: [str(x) for x in a])
    return Case(id_, make, words, source)


def _flow(*extra: str) -> Callable:
    return lambda d, fx: ["flow", str(fx["map"]), "--cache-dir", str(d / "c"), *extra]


def _tuio(*extra: str) -> list[str]:
    return ["tuio", "--seconds", "0.3", *extra]


def _knob(*extra: str) -> Callable:
    return lambda d, fx: ["knob", "--trials", "1", "--log", str(d / "k.jsonl"), *extra]


def _proj(*extra: str) -> Callable:
    """The projector process, headless, ending by itself when nothing connects."""
    return lambda d, fx: [
        "projector",
        "--headless",
        "--scene",
        "black",
        "--socket",
        str(d / "p.sock"),
        "--exit-without-console-s",
        "0.5",
        *extra,
    ]


def _cal(*extra: str) -> Callable:
    return lambda d, fx: ["projector", "--calibration", str(d / "cal.json"), *extra]


def _synth(*extra: str) -> Callable:
    return lambda d, fx: [
        "gestures",
        "synth",
        "--subjects",
        "1",
        "--reps",
        "1",
        "--gestures",
        "one_finger",
        "--out",
        str(d / "ds"),
        *extra,
    ]


DIGITS = "9" * 5000
CASES: list[Case] = [
    # ---- issue 25
    _c("flow-min-contrast-1e308", _flow("--from", "51", "--to", "52", "--rule", "paper",
       "--min-contrast-db", "1e308"), "flow --min-contrast-db", "1e308", source="issue"),
    _c("flow-min-contrast-nan", _flow("--from", "51", "--to", "52", "--min-contrast-db", "nan"),
       "--min-contrast-db", "nan", source="issue"),
    _c("flow-min-contrast-negative", _flow("--from", "51", "--to", "52", "--rule", "paper",
       "--min-contrast-db", "-1"), "--min-contrast-db", "-1", source="issue"),
    _c("tuio-port-negative", _tuio("--port", "-1"), "tuio --port", "-1", source="issue"),
    _c("tuio-port-99999", _tuio("--port", "99999"), "--port", "99999", "65535", source="issue"),
    _c("tuio-port-0", _tuio("--port", "0"), "--port", "0", source="issue"),
    _c("knob-sectors-0", _knob("--sectors", "0"), "knob --sectors", "0", source="issue"),
    _c("projector-fps-nan", _proj("--fps", "nan"), "projector --fps", "nan", source="issue"),
    _c("projector-fps-0", _proj("--fps", "0"), "--fps", "0", source="issue"),
    _c("synth-workers-negative", _synth("--workers", "-1"), "--workers", "-1", source="issue"),
    _c("demo-seconds-1e308", ["demo", "knob", "--seconds", "1e308"], "demo --seconds", "1e308",
       source="issue"),
    # ---- our own, on the same surfaces
    _c("tuio-port-fraction", _tuio("--port", "3333.5"), "--port", "3333.5", "whole"),
    _c("tuio-port-5000-digits", _tuio("--port", DIGITS), "--port", "5000 characters"),
    _c("tuio-port-word", _tuio("--port", "osc"), "--port", "osc"),
    _c("tuio-port-missing-value", ["tuio", "--port"], "tuio --port", "expected one argument"),
    _c("tuio-seconds-inf", ["tuio", "--seconds", "inf"], "--seconds", "inf"),
    _c("tuio-seconds-negative", ["tuio", "--seconds", "-5"], "--seconds", "-5"),
    _c("tuio-host-256", _tuio("--host", "256.1.1.1"), "--host", "256.1.1.1"),
    _c("tuio-host-space", _tuio("--host", "my host"), "--host", "my host"),
    _c("tuio-host-unresolvable", _tuio("--host", "no-such-host.invalid"), "no-such-host.invalid"),
    _c("knob-sectors-100000", _knob("--sectors", "100000"), "--sectors", "100000"),
    _c("knob-sectors-empty", _knob("--sectors", ""), "--sectors", "''"),
    _c("knob-sectors-typo", _knob("--sektors", "8"), "--sektors"),
    _c("knob-trials-0", _knob("--trials", "0"), "--trials", "0"),
    _c("knob-distance-nan", _knob("--distance", "nan"), "--distance", "nan"),
    _c("knob-seed-negative", _knob("--seed", "-1"), "--seed", "-1"),
    _c("knob-seed-huge", _knob("--seed", "1" + "0" * 30), "--seed"),
    _c("knob-max-time-inf", _knob("--max-time", "inf"), "--max-time", "inf"),
    _c("demo-seconds-negative", ["demo", "knob", "--seconds", "-1"], "--seconds", "-1"),
    _c("demo-minutes-nan", ["demo", "soak", "--minutes", "nan"], "--minutes", "nan"),
    _c("demo-sectors-0", ["demo", "knob", "--sectors", "0", "--seconds", "1"], "--sectors", "0"),
    _c("projector-fps-inf", _proj("--fps", "inf"), "--fps", "inf"),
    _c("projector-fps-1e9", _proj("--fps", "1e9"), "--fps", "1e9"),
    _c("projector-screen-negative", _proj("--screen", "-1"), "--screen", "-1"),
    _c("projector-heartbeat-0", _proj("--heartbeat-s", "0"), "--heartbeat-s", "0"),
    _c("projector-seconds-nan", ["projector", "--show", "black", "--seconds", "nan"],
       "--seconds", "nan"),
    _c("projector-corner-nan", _cal("--set-corner", "1", "nan", "0"), "--set-corner", "nan"),
    _c("projector-corner-2.5", _cal("--set-corner", "2.5", "0", "0"), "--set-corner", "2.5"),
    _c("projector-point-1e308", _cal("--add-point", "1e308", "0", "0", "0"), "--add-point"),
    _c("projector-event-deep", _proj("--event", "[" * 30000 + "]" * 30000), "--event",
       "nested"),
    _c("projector-size-0x0", _proj("--size", "0x0"), "--size 0x0"),
    _c("synth-seed-negative", _synth("--seed", "-1"), "--seed", "-1"),
    _c("synth-workers-100000", _synth("--workers", "100000"), "--workers", "100000"),
    _c("synth-exposure-nan", _synth("--exposure-ms", "nan"), "--exposure-ms", "nan"),
    _c("synth-light-scale-0", _synth("--light-scale", "0"), "--light-scale", "0"),
    _c("synth-sessions-0", _synth("--vary", "--sessions", "0"), "--sessions", "0"),
    _c("synth-left-handed-negative", _synth("--left-handed", "-1"), "--left-handed", "-1"),
    _c("calibrate-columns-0", lambda d, fx: ["gestures", "calibrate", "--columns", "0", "--out",
       str(d / "c.json")], "--columns", "0"),
    _c("calibrate-margin-nan", lambda d, fx: ["gestures", "calibrate", "--margin-mm", "nan",
       "--out", str(d / "c.json")], "--margin-mm", "nan"),
    _c("train-harmonics-negative", lambda d, fx: ["gestures", "train", str(d), "--harmonics",
       "-1", "--out", str(d / "m.skops")], "--harmonics", "-1"),
    _c("eval-frames-0", lambda d, fx: ["gestures", "eval", str(d), "--frames", "0"],
       "--frames", "0"),
    _c("plate-count-0", ["plate", "modes", "--count", "0"], "--count", "0"),
    _c("plate-count-10-million", ["plate", "modes", "--count", "10000000"], "--count"),
    _c("plate-aspect-nan", ["plate", "modes", "--aspect", "nan"], "--aspect", "nan"),
    _c("bench-minutes-nan", ["bench", "console", "--minutes", "nan"], "--minutes", "nan"),
    _c("tables-zeta-0", lambda d, fx: ["tables", "build", str(fx["map"]), "--out",
       str(d / "t.npz"), "--zeta", "0"], "--zeta", "0"),
    _c("tables-zeta-nan", lambda d, fx: ["tables", "build", str(fx["map"]), "--out",
       str(d / "t.npz"), "--zeta", "nan"], "--zeta", "nan"),
    _c("flow-hand-mm-nan", _flow("--hand", "300,200", "--direction", "left", "--hand-mm", "nan"),
       "--hand-mm", "nan"),
    _c("flow-ringdown-negative", _flow("--from", "51", "--to", "52", "--ringdown-k", "-1"),
       "--ringdown-k", "-1"),
    _c("frf-export-gain-0", lambda d, fx: ["frf", "export", str(fx["map"]), "--out",
       str(d / "u"), "--gain", "0"], "--gain", "0"),
    _c("frf-export-gain-inf", lambda d, fx: ["frf", "export", str(fx["map"]), "--out",
       str(d / "u"), "--gain", "inf"], "--gain", "inf"),
    _c("estop-timeout-nan", ["estop", "--timeout", "nan"], "--timeout", "nan"),
]  # fmt: skip


@pytest.fixture(scope="module")
def fx(tmp_path_factory) -> dict:
    """A small valid vibration map (84 points, 27 bins)."""
    import numpy as np

    from console.files.vibration_map import save_map
    from plugins.vibrotactile.analytic_plate import analytic_map

    d = tmp_path_factory.mktemp("numbers")
    return {"map": save_map(d / "map.npz", analytic_map(freq_hz=np.array(F_HZ)))}


def tally(name: str, code: int, clear: bool, line: str) -> None:
    if path := os.environ.get("HAPTABLE_MALFORMED_TALLY"):
        what = {0: "accepted", 3: "internal"}.get(code, "line" if clear else f"exit{code}-unclear")
        with open(path, "a") as f:
            f.write(f"cli-{name}\t{what}\t{line[:300]!r}\n")


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_a_bad_number_is_one_line_and_exit_2(case, fx, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    argv = case.argv(tmp_path, fx)
    capsys.readouterr()
    code = main(argv)
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    line = lines[0] if lines else ""
    clear = (
        code == 2
        and len(lines) == 1
        and line.startswith("haptable: error: ")
        and all(w in line for w in case.words)
    )
    tally(case.id, code, clear, line)
    assert code == 2, err
    assert len(lines) == 1, err
    assert line.startswith("haptable: error: "), line
    assert "Traceback" not in err
    for w in case.words:
        assert w in line, (w, line)


# ---------------------------------------------------------------- the one place
def _number_actions(parser: argparse.ArgumentParser, path: tuple[str, ...] = ()):
    for a in parser._actions:
        if isinstance(a, argparse._SubParsersAction):
            for name, sub in a.choices.items():
                yield from _number_actions(sub, (*path, name))
        else:
            yield path, a


#: commands whose numbers other work moves to console.core.options (issue 25's studies part)
PENDING = {("study", "run")}


def test_every_number_option_is_declared_with_its_range(plugins):
    """No ``type=int`` / ``type=float``: a plain converter takes NaN, infinity, -1."""
    from console.cli import core_commands
    from console.config.plugins import load_plugins

    parser = build_parser(load_plugins(core=core_commands))
    plain = [
        f"haptable {' '.join(path)} {'/'.join(a.option_strings) or a.dest}"
        for path, a in _number_actions(parser)
        if a.type in (int, float) and path not in PENDING
    ]
    assert not plain, "declare these with console.core.options (finite_float, integer, ...):\n" + (
        "\n".join(plain)
    )


@pytest.mark.parametrize(
    ("conv", "text", "value"),
    [
        (port(), "3333", 3333),
        (port(), " 80 ", 80),
        (port(), "1e3", 1000),
        (integer(0, 10), "+7", 7),
        (integer(), "1_000", 1000),
        (finite_float(0, 200), "0", 0.0),
        (finite_float(0, 200), "200", 200.0),
        (finite_float(0, above=True), "1e-300", 1e-300),
        (seconds(zero="until Ctrl-C"), "0", 0.0),
        (integer(0, MAX_SEED), str(MAX_SEED), MAX_SEED),
    ],
)
def test_good_values_pass(conv: Number, text: str, value):
    got = conv(text)
    assert got == value and type(got) is type(value)


@pytest.mark.parametrize(
    ("conv", "text", "says"),
    [
        (port(), "0", "0: out of range; give a whole number from 1 to 65535"),
        (port(), "65536", "out of range"),
        (port(), "-0", "out of range"),
        (port(), "1.5", "not a whole number"),
        (port(), "", "'': not a number"),
        (port(), "0x50", "not a number"),
        (port(), "1e400", "not a finite number"),
        (finite_float(0, 200, unit="dB"), "nan", "nan: not a finite number; give a number "
         "from 0 to 200 dB"),
        (finite_float(0, 200), "-inf", "not a finite number"),
        (finite_float(0, 200), "200.0001", "out of range"),
        (finite_float(0, above=True), "0", "above 0"),
        (finite_float(0, above=True), "-0.0", "out of range"),
        (integer(0, 10), "9" * 5000, "(5000 characters): not a number"),
        (integer(0, 10), "1\n2", "1\\n2"),
        (seconds(zero="until Ctrl-C"), "1e308", "from 0 to 604800 s (0: until Ctrl-C)"),
    ],
)  # fmt: skip
def test_bad_values_say_what_to_give(conv: Number, text: str, says: str):
    with pytest.raises(argparse.ArgumentTypeError) as err:
        conv(text)
    assert says in str(err.value)
    assert "\n" not in str(err.value)


def test_an_option_over_a_profile_key_has_the_keys_range():
    f = Field("int", 16, min=2, max=64)
    assert from_field(f)("64") == 64
    with pytest.raises(argparse.ArgumentTypeError, match="from 2 to 64"):
        from_field(f)("1")
    assert from_field(Field("float", 60.0, min=1, max=240))("59.5") == 59.5


def test_usage_line_names_the_command_and_option():
    assert usage_line("haptable knob", "argument --sectors: 0 is out of range; give x") == (
        "knob --sectors: 0 is out of range; give x"
    )
    assert usage_line("haptable", "unrecognized arguments: --x") == (
        "unrecognized arguments: --x (see `haptable --help`)"
    )
    line = usage_line("haptable gestures synth", "the following arguments are required: --out")
    assert (
        line.startswith("gestures synth: the following")
        and "haptable gestures synth --help" in line
    )


def test_help_still_prints_and_exits_0(capsys):
    with pytest.raises(SystemExit) as e:
        main(["tuio", "--help"])
    assert e.value.code == 0
    out = capsys.readouterr().out
    assert "--port" in out
