"""The signal library file: validated like a profile, written atomically, never losing
the operator's other entries; built-in signals read-only."""

from __future__ import annotations

import tomllib

import pytest

from console.config.signal_library import (
    BUILTIN,
    add_signal,
    get_signal,
    library_path,
    load_library,
    read_library,
    remove_signal,
)
from console.core.errors import UserError
from console.files.paths import profile_config_dir
from console.signals.expr import parse


def test_library_lives_in_the_profiles_config_dir():
    assert library_path("sim") == profile_config_dir("sim", "signals.toml")


def test_add_show_remove_keeps_other_entries(tmp_path):
    path = tmp_path / "signals.toml"
    assert list(load_library(path)) == list(BUILTIN)  # no file: the built-ins
    add_signal(path, "pulse", "sine(250 Hz, 40 V, 0.5 s) * ramp(10 ms)", 'three "quoted" \\ ok')
    add_signal(path, "buzz", "noise(5 V, 1 s, seed=2) * ramp(5 ms)")
    lib = load_library(path)
    assert [n for n in lib if not lib[n].builtin] == ["buzz", "pulse"]
    assert get_signal(path, "pulse").description == 'three "quoted" \\ ok'
    assert tomllib.loads(path.read_text())["signals"]["buzz"]["expr"].startswith("noise(")
    with pytest.raises(UserError, match="already in"):
        add_signal(path, "pulse", "silence(1 s)")
    add_signal(path, "pulse", "silence(1 s)", replace=True)
    assert get_signal(path, "pulse").expr == "silence(1 s)"
    remove_signal(path, "pulse")
    assert "pulse" not in load_library(path) and "buzz" in load_library(path)
    with pytest.raises(UserError, match="did you mean 'buzz'"):
        get_signal(path, "buzzz")
    leftovers = [p.name for p in tmp_path.iterdir() if p.name.startswith(".signals")]
    assert leftovers == []  # the temporary file was renamed over the library


def test_builtins_are_read_only_and_valid(tmp_path):
    path = tmp_path / "signals.toml"
    for e in BUILTIN.values():
        parse(e.expr)
    with pytest.raises(UserError, match="built-in"):
        add_signal(path, "sweep", "silence(1 s)")
    with pytest.raises(UserError, match="built-in"):
        remove_signal(path, "sweep")


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("[other]\nx = 1\n", "unknown key 'other' at the top"),
        ("[signals.a\n", "not valid TOML"),
        ("signals = 3\n", "write [signals.NAME] tables"),
    ],
)  # fmt: skip
def test_unreadable_library_files_get_one_line_and_are_never_rewritten(tmp_path, text, says):
    path = tmp_path / "signals.toml"
    path.write_text(text)
    with pytest.raises(UserError) as err:
        load_library(path)
    msg = str(err.value)
    assert says in msg and str(path.name) in msg and "\n" not in msg
    with pytest.raises(UserError):
        add_signal(path, "new", "silence(1 s)")
    assert path.read_text() == text  # the operator's file stays as it was


GOOD = '[signals.good]\nexpr = "silence(1 s)"\n\n'


@pytest.mark.parametrize(
    ("text", "says"),
    [
        ("[signals.a]\nexpr = \"sine(1 Hz, 1 V, 1 s)\"\ncolour = 3\n", "[signals.a] unknown key 'colour'"),
        ("[signals.a]\nexprr = \"x\"\n", "did you mean 'expr'?"),
        ("[signals.a]\nexpr = 3\n", "[signals.a] expr = 3: give the signal as a string"),
        ("[signals.a]\ndescription = \"x\"\n", "expr = (missing)"),
        ("[signals.a]\nexpr = \"sine(250, 1 V, 1 s)\"\n", "frequency 250 needs a unit"),
        ("[signals.\"bad name\"]\nexpr = \"silence(1 s)\"\n", "signal name"),
        ("[signals.sweep]\nexpr = \"silence(1 s)\"\n", "built-in"),
    ],
)  # fmt: skip
def test_a_bad_entry_is_one_line_and_the_others_stay_usable(tmp_path, text, says):
    path = tmp_path / "signals.toml"
    path.write_text(GOOD + text)
    bad_table = tomllib.loads(text)["signals"]
    lib = read_library(path)
    assert "good" in lib.entries and len(lib.problems) == 1
    (msg,) = lib.problems.values()
    assert says in msg and path.name in msg and "\n" not in msg
    assert get_signal(path, "good").expr == "silence(1 s)"
    # a change keeps the entry that does not validate as it was written
    add_signal(path, "new", "silence(2 s)")
    kept = tomllib.loads(path.read_text())["signals"]
    assert {k: kept[k] for k in bad_table} == bad_table
    assert set(kept) == {"good", "new", *bad_table}
    (name,) = bad_table
    remove_signal(path, name)  # and it can be removed by its name
    assert not read_library(path).problems and "good" in load_library(path)


def test_bad_names_and_descriptions(tmp_path):
    path = tmp_path / "signals.toml"
    for bad in ("", "a b", "-x", "x" * 41, "ä/"):
        with pytest.raises(UserError, match="signal name"):
            add_signal(path, bad, "silence(1 s)")
    with pytest.raises(UserError, match="one printable line"):
        add_signal(path, "ok", "silence(1 s)", "two\nlines")
    with pytest.raises(UserError, match="needs a unit"):
        add_signal(path, "ok", "silence(1)")
    assert not path.exists()


def test_a_failed_write_leaves_the_library_as_it_was(tmp_path, monkeypatch):
    import console.files.atomic

    path = tmp_path / "signals.toml"
    add_signal(path, "keep", "silence(1 s)")
    before = path.read_bytes()

    def broken_replace(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(console.files.atomic.os, "replace", broken_replace)
    with pytest.raises(UserError, match="cannot write: No space left on device"):
        add_signal(path, "new", "silence(2 s)")
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["signals.toml", "signals.toml.lock"]
