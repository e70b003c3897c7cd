"""Bad input in a run's folder (issue 25): ``plan.json``, ``participant.json`` and
``trials.jsonl`` damaged, edited or replaced by something that is no file. Resuming and
analysing each says one line naming the file (the line of ``trials.jsonl``), the key,
the value and the fix; never a traceback, a hang or a silently skipped line; nothing
already recorded is lost or rewritten."""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from pathlib import Path

import pytest

from console.core.errors import UserError
from plugins.studies import analysis as an
from plugins.studies.runner import Answer, run_plan
from plugins.studies.start import prepare
from plugins.studies.store import resume_text

FILES = ("plan.json", "participant.json", "trials.jsonl")


class Player:
    def play(self, trial, attempt):
        return {}


class Right:
    """Answers every trial right (the trial's direction)."""

    def answer(self, trial, played, replays_left, control):
        return Answer(response=trial["direction"], response_time_s=0.5)

    def rate(self, item, q, records, control):
        return 4


def _resume(out: Path, protocol: Path) -> dict:
    """``haptable study run`` again: prepare (the stored plan) and run one more trial."""
    prep = prepare(str(protocol), "P01", out, simulate=True)
    resume_text(prep.plan, prep.files.events())
    return run_plan(
        prep.files, prep.plan, prep.participant, player=Player(), responder=Right(), limit=1
    )


def _analyze(out: Path) -> dict:
    return an.analyze(an.load([out / "P01"]))


@pytest.fixture
def run(tmp_path, small_exp2):
    """A simulated participant's run of the small exp2 stopped after 3 of 6 trials."""
    out = tmp_path / "out"
    prep = prepare(str(small_exp2), "P01", out, simulate=True)
    res = run_plan(
        prep.files, prep.plan, prep.participant, player=Player(), responder=Right(), limit=3
    )
    assert res["done"] == 3
    return out


def _lines(d: Path) -> list[bytes]:
    return (d / "trials.jsonl").read_bytes().rstrip(b"\n").split(b"\n")


def _insert(d: Path, at: int, raw: bytes) -> None:
    lines = _lines(d)
    lines.insert(at, raw)
    (d / "trials.jsonl").write_bytes(b"\n".join(lines) + b"\n")


def _done(d: Path, **change) -> bytes:
    rec = next(json.loads(x) for x in _lines(d) if json.loads(x)["event"] == "done")
    return json.dumps({**rec, **change}).encode()


def _edit_done(**change) -> Callable[[Path], None]:
    return lambda d: _insert(d, 2, _done(d, **change))


def _byte_ff(name: str) -> Callable[[Path], None]:
    def f(d: Path) -> None:
        b = (d / name).read_bytes()
        (d / name).write_bytes(b[:20] + b"\xff" + b[20:])

    return f


def _json(name: str, fn: Callable) -> Callable[[Path], None]:
    def f(d: Path) -> None:
        (d / name).write_text(json.dumps(fn(json.loads((d / name).read_text()))))

    return f


def _plan_trials(fn: Callable) -> Callable[[Path], None]:
    return _json("plan.json", lambda p: {**p, "trials": [fn(t) for t in p["trials"]]})


def _replace(name: str, kind: str) -> Callable[[Path], None]:
    def f(d: Path) -> None:
        p = d / name
        p.unlink()
        if kind == "fifo":
            os.mkfifo(p)
        elif kind == "zero":
            p.symlink_to("/dev/zero")
        elif kind == "dir":
            p.mkdir()
        elif kind == "empty":
            p.write_bytes(b"")
        elif kind == "huge":
            with open(p, "wb") as fh:
                fh.truncate(300 * 2**20)

    return f


def _nested(d: Path) -> None:
    _insert(d, 2, b"[" * 100_000 + b"]" * 100_000)


def _raw_done(d: Path, old: bytes, new: bytes) -> None:
    _insert(d, 2, _done(d, trial=0).replace(old, new))


# (id, change, the parts of the one line)
BAD = [
    # issue 25, internal errors
    (
        "trials-0xff",
        _byte_ff("trials.jsonl"),
        r"trials.jsonl: line 1: byte 0xff \(byte 21 of the line\) is not UTF-8 text: the file is damaged; restore the line",
    ),
    ("plan-0xff", _byte_ff("plan.json"), r"plan.json: line \d+: byte 0xff .*restore it"),
    ("participant-0xff", _byte_ff("participant.json"), r"participant.json: line \d+: byte 0xff"),
    (
        "done-trial-x",
        _edit_done(trial="x"),
        r'line 3: trial = "x": must be an integer >= 0; restore',
    ),
    ("done-trial-null", _edit_done(trial=None), r"line 3: trial = null: must be an integer"),
    ("plan-a-list", _json("plan.json", lambda p: [p]), r"plan.json: the file is a list, not an"),
    (
        "plan-no-trials",
        _json("plan.json", lambda p: {k: v for k, v in p.items() if k != "trials"}),
        r"plan.json: trials is missing; restore it or start a new --out",
    ),
    (
        "participant-a-list",
        _json("participant.json", lambda p: [p]),
        r"participant.json: the file is a list",
    ),
    # issue 25, silently accepted
    ("garbage-line", lambda d: _insert(d, 2, b"garbage"), r"trials.jsonl: line 3: not valid JSON"),
    (
        "json-list-line",
        lambda d: _insert(d, 2, b"[1, 2]"),
        r"trials.jsonl: line 3: a JSON list, not an event",
    ),
    ("done-trial-99999", _edit_done(trial=99999), r"line 3: trial = 99999: not in the plan"),
    # issue 25, files that are no files
    *[
        (f"{name}-{kind}", _replace(name, kind), rf"{name}: {what}, not a")
        for name in FILES
        for kind, what in (
            ("fifo", r"a FIFO \(named pipe\)"),
            ("zero", "a character device"),
            ("dir", "a folder"),
        )
    ],
    # beyond the issue
    ("done-trial-true", _edit_done(trial=True), r"line 3: trial = true: must be an integer"),
    (
        "done-trial-1e400",
        lambda d: _raw_done(d, b'"trial": 0', b'"trial": 1e400'),
        r"line 3: trial = Infinity: must be an integer",
    ),
    (
        "done-trial-5000-digits",
        lambda d: _raw_done(d, b'"trial": 0', b'"trial": ' + b"9" * 5000),
        r"line 3: not valid JSON \(Exceeds the limit",
    ),
    ("line-nested-100000", _nested, r"line 3: nested deeper than 32 levels"),
    (
        "duplicate-key",
        lambda d: _insert(d, 2, _done(d)[:-1] + b', "trial": 4}'),
        r"line 3: key 'trial' appears twice",
    ),
    (
        "unknown-event",
        lambda d: _insert(d, 2, b'{"event": "bogus", "trial": 1}'),
        r'line 3: event = "bogus": must be one of',
    ),
    (
        "string-line",
        lambda d: _insert(d, 2, b'"done"'),
        r'line 3: the value "done", not an event \(a JSON object\)',
    ),
    (
        "start-trial-x",
        lambda d: _insert(
            d, 9, b'{"event": "start", "experiment": "exp2", "participant": "P01", "trial": "x"}'
        ),
        r'line \d+: trial = "x": must be an integer',
    ),
    (
        "interrupted-trial-99999",
        lambda d: _insert(
            d,
            9,
            b'{"event": "interrupted", "experiment": "exp2", "participant": "P01", "trial": 99999}',
        ),
        r"trial = 99999: not in the plan \(plan.json has trials 0..5\)",
    ),
    (
        "done-of-another-participant",
        _edit_done(participant="P02"),
        r'line 3: participant = "P02" but this folder\'s plan.json has "P01"',
    ),
    (
        "done-of-another-experiment",
        _edit_done(experiment="exp1"),
        r'line 3: experiment = "exp1" but this folder\'s plan.json has "exp2"',
    ),
    (
        "done-direction-not-the-plan-s",
        _edit_done(direction="down"),
        r"line 3: direction = \"down\" but plan.json's trial 0 has \"up\"",
    ),
    (
        "done-response-not-an-answer",
        _edit_done(response="sideways"),
        r'line 3: response = "sideways": the plan\'s answers are up, down, left, right',
    ),
    (
        "done-correct-but-wrong",
        _edit_done(response="down"),
        r'line 3: correct = true but response "down" is not the direction "up"',
    ),
    ("done-replays--3", _edit_done(replays=-3), r"line 3: replays = -3: must be an integer >= 0"),
    (
        "done-response-time-NaN",
        lambda d: _raw_done(d, b'"response_time_s": 0.5', b'"response_time_s": NaN'),
        r"line 3: response_time_s = NaN: must be a number >= 0 or null",
    ),
    (
        "trials-300MB",
        _replace("trials.jsonl", "huge"),
        r"trials.jsonl: 300.0 MB is too large for a trials file .*; restore the file the run wrote",
    ),
    (
        "plan-index-not-its-place",
        _plan_trials(lambda t: {**t, "index": 7} if t["index"] == 4 else t),
        r"plan.json: trials\[4\]\.index = 7: must be 4",
    ),
    (
        "plan-stimulus-without-centre",
        _plan_trials(lambda t: {**t, "stimulus": {"effect": "hand_flow"}}),
        r"plan.json: trials\[0\]\.stimulus\.center_mm is missing",
    ),
    ("plan-empty-file", _replace("plan.json", "empty"), r"plan.json: empty file, not a study plan"),
    (
        "plan-factors-a-list",
        _json("plan.json", lambda p: {**p, "factors": {"main": ["region"]}}),
        r'plan.json: factors.main = \["region"\]: must be an object',
    ),
    (
        "plan-no-trial",
        _json("plan.json", lambda p: {**p, "trials": []}),
        r"plan.json: 0 trials; a plan has 1..100000",
    ),
    (
        "plan-duplicate-key",
        lambda d: (d / "plan.json").write_text((d / "plan.json").read_text()[:-2] + ', "seed": 5}'),
        r"plan.json: key 'seed' appears twice",
    ),
    (
        "participant-of-another",
        _json("participant.json", lambda p: {**p, "id": "P02"}),
        r'participant.json: id = "P02" but this folder is P01\'s',
    ),
    (
        "participant-age-old",
        _json("participant.json", lambda p: {**p, "age": "old"}),
        r'participant.json: age = "old": must be an integer from 1 to 120',
    ),
    (
        "participant-empty",
        _replace("participant.json", "empty"),
        r"participant.json: empty file, not a participant record",
    ),
]
RESUME_ONLY = [
    (
        "plan-responses-a-string",  # a simulated observer was refused forever: a hang
        _json("plan.json", lambda p: {**p, "responses": "up"}),
        r'plan.json: responses = "up": must be a list of strings',
    ),
    (
        "plan-seed-x",
        _json("plan.json", lambda p: {**p, "seed": "x"}),
        r'plan.json: seed = "x": must be an integer >= 0; restore it',
    ),
    (
        "plan-of-another-participant",
        _json("plan.json", lambda p: {**p, "participant": "P02"}),
        r"plan.json: participant = 'P02' but this run has 'P01'",
    ),
    (
        "plan-trials-edited",
        _plan_trials(lambda t: {**t, "replays_allowed": 9}),
        r"plan.json: its trials or questionnaires are not those of this protocol",
    ),
    (
        "participant-simulated-no",
        _json("participant.json", lambda p: {**p, "simulated": "no"}),
        r'participant.json: simulated = "no": must be true or false',
    ),
]
ANALYZE_ONLY = [  # the analysis reads columns the runner does not
    ("done-correct-no", _edit_done(correct="no"), r'line 3: correct = "no": must be true or false'),
    ("done-replays-x", _edit_done(replays="x"), r'line 3: replays = "x": must be an integer'),
    (
        "done-response-time-fast",
        _edit_done(response_time_s="fast"),
        r'line 3: response_time_s = "fast": must be a number',
    ),
    (
        "done-direction-a-list",
        _edit_done(direction=["up"]),
        r'line 3: direction = \["up"\]: must be a string or null',
    ),
    ("done-phase-null", _edit_done(phase=None), r"line 3: phase = null: must be a string"),
]


def _snapshot(d: Path) -> dict[str, bytes]:
    out = {}
    for name in FILES:
        p = d / name
        if p.is_file() and not p.is_symlink() and p.stat().st_size < 2**20:
            out[name] = p.read_bytes()
    return out


def _refused(action: Callable[[], object], d: Path, message: str) -> None:
    before = _snapshot(d)
    with pytest.raises(UserError, match=message) as err:
        action()
    assert "\n" not in str(err.value)
    assert _snapshot(d) == before  # nothing recorded is lost, rewritten or added


@pytest.mark.parametrize(
    ("change", "message"), [c[1:] for c in BAD + RESUME_ONLY], ids=[c[0] for c in BAD + RESUME_ONLY]
)
def test_a_resume_refuses_a_bad_run_folder_in_one_line(run, small_exp2, change, message):
    change(run / "P01")
    _refused(lambda: _resume(run, small_exp2), run / "P01", message)


@pytest.mark.parametrize(
    ("change", "message"),
    [c[1:] for c in BAD + ANALYZE_ONLY],
    ids=[c[0] for c in BAD + ANALYZE_ONLY],
)
def test_the_analysis_refuses_a_bad_run_folder_in_one_line(run, change, message):
    change(run / "P01")
    _refused(lambda: _analyze(run), run / "P01", message)


def test_a_torn_line_is_a_crash_s_trace_last_or_followed_by_later_appends(run, small_exp2):
    """Only a line the runner's append left cut short (a JSON object's start, perhaps with
    a file system's zeros) is skipped: as the last line, and where the resume's next
    append left it; the analysis says so."""
    d = run / "P01"
    whole = _done(d, trial=3).decode()
    with open(d / "trials.jsonl", "ab") as f:
        f.write(whole[:40].encode())  # the crash
    assert _resume(run, small_exp2)["done"] == 4  # the next append goes on after it
    with open(d / "trials.jsonl", "ab") as f:
        f.write(whole[:17].encode() + b"\0" * 100)
    assert _resume(run, small_exp2)["done"] == 5
    res = _analyze(run)
    assert any("trials.jsonl lines 7, 10 cut short by a crash" in n for n in res["notes"])
    assert res["accuracy"]["participants"][0]["trials"] == 3  # main-phase trials 2, 3, 4


@pytest.mark.parametrize(
    "cut", [b'{"event": "done", "tri', b'{"event": "done", "trial": 1', b'{"a": tr', b"\0\0\0"]
)
def test_a_torn_line_is_any_cut_of_an_event(run, cut):
    _insert(run / "P01", 2, cut)
    notes = _analyze(run)["notes"]
    assert any("trials.jsonl line 3 cut short by a crash (skipped" in n for n in notes)


def test_the_analysis_reads_done_records_completed_from_their_plan(run):
    """A done record without the trial's columns (they are in the plan) is analysed with
    the plan's: the file contract needs only what the plan does not say."""
    d = run / "P01"
    lines = [json.loads(x) for x in _lines(d)]
    keep = ("event", "participant", "experiment", "phase", "trial", "response", "correct")
    lines = [{k: e[k] for k in keep if k in e} if e["event"] == "done" else e for e in lines]
    (d / "trials.jsonl").write_text("".join(json.dumps(e) + "\n" for e in lines))
    res = _analyze(run)
    assert res["accuracy"]["by_region"][0]["region"] == "R4"


class Knob:
    def play(self, trial, attempt):
        return {"completion_time_s": 1.0, "overshoots": 1, "recovery_time_s": 0.3, "detents": 3}


@pytest.fixture
def knob_run(tmp_path):
    """A simulated knob run of one distance and one sector count: 4 trials, a
    questionnaire (7-point, 14 items) after each."""
    from plugins.studies import protocol as P

    text = P.find("knob").read_text().replace("repetitions = 6", "repetitions = 1")
    text = text.replace("sectors = [8, 16, 32]", "sectors = [8]").replace(
        "[135, 270, 450]", "[135]"
    )
    path = tmp_path / "knob-small.toml"
    path.write_text(text)
    out = tmp_path / "out"
    prep = prepare(str(path), "P01", out, simulate=True)
    res = run_plan(
        prep.files, prep.plan, prep.participant, player=Knob(), responder=Right(), limit=2
    )
    assert res["done"] == 2
    return out, path


def _edit_event(kind: str, **change) -> Callable[[Path], None]:
    def f(d: Path) -> None:
        lines = _lines(d)
        i = next(i for i, x in enumerate(lines) if json.loads(x)["event"] == kind)
        lines[i] = json.dumps({**json.loads(lines[i]), **change}).encode()
        (d / "trials.jsonl").write_bytes(b"\n".join(lines) + b"\n")

    return f


KNOB_BAD = [
    (
        "questionnaire-unknown-item",
        _edit_event("questionnaire", item=9),
        r'line 3: category "effectiveness" item 9: not an item of the questionnaire after trial 0',
    ),
    (
        "questionnaire-score-above-the-scale",
        _edit_event("questionnaire", score=9),
        r"line 3: score = 9: give 1..7",
    ),
    (
        "questionnaire-after-no-questionnaire",
        _edit_event("questionnaire", after_trial=99),
        r"line 3: after_trial = 99: plan.json asks the questionnaire after 0, 1, 2, 3; restore",
    ),
    (
        "questionnaire-of-another-condition",
        _edit_event("questionnaire", condition="HD+VF"),
        r'line 3: condition = "HD\+VF" but the questionnaire after trial 0 is for',
    ),
    (
        "questionnaire-score-x",
        _edit_event("questionnaire", score="x"),
        r'line 3: score = "x": must be an integer from 1 to 11',
    ),
    (
        "done-distance-not-the-plan-s",
        _edit_event("done", distance_deg=999.0),
        r"line 2: distance_deg = 999.0 but plan.json's trial 0 has 135",
    ),
    (
        "done-overshoots-many",
        _edit_event("done", overshoots="many"),
        r'line 2: overshoots = "many": must be an integer >= 0',
    ),
    (
        "done-completion-slow",
        _edit_event("done", completion_time_s="slow"),
        r'line 2: completion_time_s = "slow": must be a number >= 0 or null',
    ),
    (
        "done-stimulus-a-string",
        _edit_event("done", stimulus="knob"),
        r'line 2: stimulus = "knob": must be an object',
    ),
    (
        "plan-knob-stimulus-without-sectors",
        _plan_trials(lambda t: {**t, "stimulus": {"task": "knob", "condition": "V"}}),
        r"plan.json: trials\[0\]\.stimulus\.sectors is missing",
    ),
]


@pytest.mark.parametrize(
    ("change", "message"), [c[1:] for c in KNOB_BAD], ids=[c[0] for c in KNOB_BAD]
)
def test_bad_knob_records_are_one_line_on_resume_and_analysis(knob_run, change, message):
    out, protocol = knob_run
    d = out / "P01"
    change(d)
    _refused(lambda: _analyze(out), d, message)

    def resume() -> None:
        prep = prepare(str(protocol), "P01", out, simulate=True)
        run_plan(prep.files, prep.plan, prep.participant, player=Knob(), responder=Right())

    _refused(resume, d, message)
