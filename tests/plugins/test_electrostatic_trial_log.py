"""The knob task's trial log read back: a line torn by a crash is skipped wherever it
is; any other bad line is one clear line naming the file and the line, never a
traceback (``plugins/electrostatic/trial_log.py``)."""

from __future__ import annotations

import json

import pytest

from console.plugin_api import UserError, append_json_line
from plugins.electrostatic.trial_log import read_trials


@pytest.fixture
def log(tmp_path):
    path = tmp_path / "knob_trials.jsonl"
    for k in (1, 2):
        append_json_line(path, {"trial": k, "condition": "HD+VF", "ok": True, "t": 1.5})
    return path


@pytest.mark.parametrize(
    "tail",
    [
        '{"trial": 3, "condi',  # inside a string
        '{"trial": 3, "ok": tr',  # inside a literal
        '{"trial": 3, "t": 1.',  # inside a number
        '{"trial": 3, "condition": "HD\\',  # inside an escape
        '{"trial": 3',  # between values
        "{",
        '{"trial": 3, "t": 2\0\0\0\0',  # the zeros a file system leaves
        "\0\0\0\0",
    ],
)
def test_a_torn_last_line_is_skipped_and_appends_go_on(log, tail):
    with open(log, "a", encoding="utf-8") as f:
        f.write(tail)
    assert [r["trial"] for r in read_trials(log)] == [1, 2]
    append_json_line(log, {"trial": 4})
    assert [r["trial"] for r in read_trials(log)] == [1, 2, 4]


@pytest.mark.parametrize(
    ("tail", "said"),
    [
        ('{"trial": 3, oops}', "not valid JSON"),  # garbled, not cut short
        ("garbage", "not valid JSON"),
        ("[1, 2]", "a JSON list, not a trial"),
        ("42", "the value 42, not a trial"),
        ('{"trial": "\xff"}', "not UTF-8"),
    ],
)
def test_a_garbled_line_is_one_clear_error_naming_file_and_line(log, tail, said):
    with open(log, "ab") as f:
        f.write(tail.encode("latin-1") + b"\n")
    append_json_line(log, {"trial": 5})
    with pytest.raises(UserError) as err:
        read_trials(log)
    msg = str(err.value)
    assert msg.startswith(f"{log}: line 3: ") and said in msg, msg
    assert "\n" not in msg and "move it aside" in msg


def test_a_log_that_is_no_regular_file_is_refused_in_one_line(tmp_path):
    with pytest.raises(UserError) as err:
        read_trials(tmp_path)
    assert str(tmp_path) in str(err.value) and "\n" not in str(err.value)


def test_a_missing_log_has_no_trials(tmp_path):
    assert read_trials(tmp_path / "none.jsonl") == []


def test_what_the_task_appends_reads_back(log):
    assert read_trials(log)[0] == json.loads(log.read_text().splitlines()[0])
