"""A mistyped word is met with the word meant, as it is written: one helper
(``console.core.suggest``) for every "did you mean" of the console, case-insensitive, and
the lists a user reads whole."""

from __future__ import annotations

import ast
from pathlib import Path

import console
from console.cli.main import main
from console.core.suggest import did_you_mean, suggestion


def _error(capsys, argv: list[str]) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err  # one line
    return err


def test_play_suggests_the_name_as_written(capsys):
    err = _error(capsys, ["play", "sine-pa"])
    assert "did you mean 'sine-PA'?" in err


def test_a_mistyped_option_is_met_with_the_option_meant(capsys):
    err = _error(capsys, ["doctor", "--bufer", "2"])
    assert "did you mean '--buffer'?" in err
    assert "doctor: unrecognized" in err and "(see `haptable doctor --help`)" in err
    err = _error(capsys, ["gestures", "eval", "DATA", "--cvv", "loso"])  # a nested command
    assert "did you mean '--cv'?" in err and "`haptable gestures eval --help`" in err


def test_a_mistyped_command_is_met_with_the_command_meant(capsys):
    err = _error(capsys, ["docter"])
    assert "did you mean 'doctor'?" in err
    err = _error(capsys, ["PLAY", "sweep"])
    assert "did you mean 'play'?" in err


def test_bench_suggests_a_benchmark(capsys):
    err = _error(capsys, ["bench", "lst"])
    assert "did you mean 'list'?" in err
    err = _error(capsys, ["bench", "Gate-Fil"])
    assert "did you mean 'gate-fill'?" in err


def test_bench_list_shows_each_description_whole(capsys, monkeypatch):
    from console.config.plugins import load_plugins

    monkeypatch.setenv("COLUMNS", "80")
    assert main(["bench", "list"]) == 0
    out = capsys.readouterr().out
    assert "..." not in out
    assert all(len(line) <= 80 for line in out.splitlines()), out
    flat = " ".join(out.split())
    for name, b in load_plugins().benchmarks.items():
        assert " ".join(f"{name} {b.help}".split()) in flat, name


def test_the_helper():
    names = ["sine-PA", "sine-PB", "sine-PALL", "sweep"]
    assert did_you_mean("sine-pa", names) == "sine-PA"
    assert did_you_mean("SWEEP", names) == "sweep"
    assert did_you_mean("swep", names) == "sweep"
    assert did_you_mean("xyzzy", names) is None
    assert did_you_mean("", names) is None
    assert suggestion("sine-pb", names) == " (did you mean 'sine-PB'?)"
    assert suggestion("xyzzy", names) == ""


CONSOLE = Path(console.__file__).resolve().parent


def test_one_helper_makes_every_suggestion():
    """``difflib.get_close_matches`` is called in ``console/core/suggest.py`` only."""
    found = []
    for path in sorted(CONSOLE.rglob("*.py")):
        if path.name == "suggest.py":
            continue
        for n in ast.walk(ast.parse(path.read_text())):
            name = getattr(n, "attr", None) or getattr(n, "id", None)
            if isinstance(n, ast.Attribute | ast.Name) and name == "get_close_matches":
                found.append(f"{path.relative_to(CONSOLE)}:{n.lineno}")
    assert not found, "use console.core.suggest.did_you_mean:\n" + "\n".join(found)
