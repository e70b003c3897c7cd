"""Bad input in a protocol file and on ``haptable study run``'s command line (issue 25):
one line naming the file, key or option, the value and the fix (exit 2), nothing written;
never a traceback, a hang or a value silently taken."""

from __future__ import annotations

import os
import re

import pytest

from console.core.errors import UserError
from plugins.studies import protocol as P
from plugins.studies.start import prepare

EXP1 = P.find("exp1").read_text()
KNOB = P.find("knob").read_text()


def _changed(text: str, old: str, new: str) -> str:
    assert old in text
    return text.replace(old, new, 1)


def _deep(opening: str, closing: str, inner: str = "") -> str:
    return "[study]\nname = " + opening * 3000 + inner + closing * 3000 + "\n"


SECOND_R4 = '[[regions]]\nname = "R4"\ncenter_mm = [500.0, 300.0]\nhand = "left"\n[[phases]]'
PROTOCOLS = [
    # issue 25
    ("nested-3000-arrays", lambda e2: _deep("[", "]"), "nested too deeply to read"),
    (
        "pair-level-a-list",
        lambda e2: _changed(EXP1, 'pair = ["1", "2"', 'pair = [["1"], "2"'),
        r"phases\[1\]\.factors\.pair = \['1'\]: a level is a name or a number, not a list",
    ),
    (
        "pair-2-twice",
        lambda e2: _changed(EXP1, '[[pairs]]\nname = "3"', '[[pairs]]\nname = "2"'),
        r"pairs\[3\]\.name = '2': pairs\[2\] has that name already; give each its own name",
    ),
    # beyond the issue
    ("nested-3000-inline-tables", lambda e2: _deep("{a=", "}", "1"), "nested too deeply"),
    (
        "pair-level-a-table",
        lambda e2: _changed(EXP1, 'pair = ["1", "2"', 'pair = [{a = 1}, "2"'),
        r"factors\.pair = \{'a': 1\}: a level is a name or a number",
    ),
    (
        "region-level-a-list",
        lambda e2: _changed(e2, 'region = ["R4"]', 'region = [["R4"]]'),
        r"factors\.region = \['R4'\]: a level is a name or a number",
    ),
    (
        "region-twice",
        lambda e2: _changed(e2, "[[phases]]", SECOND_R4),
        r"regions\[2\]\.name = 'R4': regions\[1\] has that name already",
    ),
    (
        "questionnaire-category-twice",
        lambda e2: _changed(KNOB, 'name = "ease of use"', 'name = "effectiveness"'),
        r"questionnaire\.categories\[1\]\.name = 'effectiveness': questionnaire\.categories"
        r"\[0\] has that name already",
    ),
    (
        "questionnaire-scale-11",  # a key per point: the Studies screen takes 1..9
        lambda e2: _changed(KNOB, "scale = 7", "scale = 11"),
        r"questionnaire\.scale = 11: give the points of the scale, 2\.\.9 \(one key each",
    ),
    (
        "an-integer-of-5000-digits",
        lambda e2: _changed(e2, "seed = 3", "seed = " + "9" * 5000),
        "a value TOML allows but no setting can hold",
    ),
    (
        "byte-0xff",
        lambda e2: _changed(e2, 'name = "exp2"', 'name = "exp\udcff"'),
        r"line 3: byte 0xff \(byte 12 of the line\) is not UTF-8 text: the file is damaged; "
        "save the protocol as UTF-8 text",
    ),
]


@pytest.mark.parametrize(
    ("make", "message"), [c[1:] for c in PROTOCOLS], ids=[c[0] for c in PROTOCOLS]
)
def test_a_bad_protocol_is_one_line(tmp_path, small_exp2, make, message):
    path = tmp_path / "bad.toml"
    path.write_bytes(make(small_exp2.read_text()).encode("utf-8", "surrogateescape"))
    with pytest.raises(UserError, match=message) as err:
        P.load(path)
    assert "\n" not in str(err.value) and str(path) in str(err.value)


@pytest.mark.parametrize(
    ("kind", "what"),
    [
        ("fifo", r"a FIFO \(named pipe\), not a study protocol"),
        ("zero", "a character device, not a study protocol"),
        ("dir", "a folder, not a study protocol"),
        ("huge", r"2.0 MB is too large for a study protocol \(at most 1.0 MB\)"),
    ],
)
def test_a_protocol_that_is_no_file_is_one_line_not_a_hang(tmp_path, kind, what):
    p = tmp_path / "p.toml"
    if kind == "fifo":
        os.mkfifo(p)
    elif kind == "zero":
        p.symlink_to("/dev/zero")
    elif kind == "dir":
        p.mkdir()
    else:
        with open(p, "wb") as f:
            f.truncate(2 * 2**20)
    with pytest.raises(UserError, match=what):
        P.load(p)


@pytest.fixture
def cli(double_plugins):
    from console.cli.main import main

    return main


KNOB_RUN = ["study", "run", "knob", "--simulate", "--participant", "P01", "--trials", "1"]
OPTIONS = [
    # issue 25
    ("row--1", KNOB_RUN, ["--row", "-1"], r"--row -1: knob's Latin square has 4 rows; give 0 to 3"),
    ("row-1e23", KNOB_RUN, ["--row", "1e23"], r"--row '1e23': give a whole number"),
    ("row-10^23", KNOB_RUN, ["--row", "1" + "0" * 23], r"--row 1000+: knob's Latin square"),
    (
        "seed--1",
        None,
        ["--seed", "-1"],
        r"--seed -1: give a whole number from 0 to 9223372036854775807",
    ),
    (
        "participant-P01-newline",
        None,
        ["--participant", "P01\n"],
        r"participant 'P01\\n': use letters",
    ),
    (
        "participant-dot-dot",  # a second new operator's try: the real fault, not the list
        None,
        ["--participant", ".."],
        r"participant '\.\.': start with a letter or digit, not '\.' \('\.' and '\.\.' name",
    ),
    # beyond the issue
    ("seed-10^30", None, ["--seed", "1" + "0" * 30], r"--seed 1000+: give a whole number from 0"),
    ("seed-1.5", None, ["--seed", "1.5"], r"--seed '1.5': give a whole number"),
    ("row-without-a-latin-square", None, ["--row", "2"], r"--row 2: exp2 has no latin_square"),
    (
        "participants-from-P01-newline",
        None,
        ["--participant", "P01\n", "--participants", "2"],
        r"participant 'P01\\n': use letters",
    ),
]


@pytest.mark.parametrize(
    ("base", "extra", "message"), [c[1:] for c in OPTIONS], ids=[c[0] for c in OPTIONS]
)
def test_bad_options_are_one_line_and_write_nothing(
    cli, capsys, tmp_path, map_file, small_exp2, base, extra, message
):
    out = tmp_path / "out"
    if base is None:
        base = ["study", "run", str(small_exp2), "--simulate", "--map", str(map_file)]
        base += ["--trials", "1"] + ([] if "--participant" in extra else ["--participant", "P01"])
    assert cli([*base, "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "internal error" not in err
    assert re.search(message, err), err
    assert not out.exists()  # nothing written


def test_a_resume_with_another_seed_or_row_is_refused(tmp_path, small_exp2):
    out = tmp_path / "out"
    prepare(str(small_exp2), "P01", out, simulate=True, seed=5)
    before = (out / "P01" / "plan.json").read_bytes()
    with pytest.raises(UserError, match=r"plan.json: seed = 5 but this run has 7; resume it as"):
        prepare(str(small_exp2), "P01", out, simulate=True, seed=7)
    prepare(str(small_exp2), "P01", out, simulate=True, seed=5)  # the same command resumes
    assert (out / "P01" / "plan.json").read_bytes() == before


def test_participant_ids_are_whole_matches(tmp_path, small_exp2):
    for bad in ("P01\n", "P01\r", "P01 ", "", "P01/..", "P０1"):
        with pytest.raises(UserError, match="use letters, digits"):
            prepare(str(small_exp2), bad, tmp_path / "out", simulate=True)
    with pytest.raises(UserError, match=r"at most 64 characters \(it has 65\)"):
        prepare(str(small_exp2), "P" * 65, tmp_path / "out", simulate=True)
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("bad", ["..", ".", ".P01", "-P01", "_P01"])
def test_a_participant_id_of_allowed_characters_says_its_real_fault(tmp_path, small_exp2, bad):
    """``..`` uses only the allowed characters: the refusal names what it breaks (its
    first character; ``.``/``..`` name no folder of their own), not the character list
    it satisfies (a new operator's try)."""
    with pytest.raises(UserError) as refused:
        prepare(str(small_exp2), bad, tmp_path / "out", simulate=True)
    said = str(refused.value)
    assert f"participant {bad!r}: start with a letter or digit, not {bad[0]!r}" in said, said
    assert "name no folder of their own" in said and "use letters" not in said, said
    assert not (tmp_path / "out").exists()
