"""The Studies screen's status after a protocol is chosen says what the folder holds for
the participant: finished (the next participant is proposed), or where s resumes; never
"s starts it with P01" when P01 is done (seventh new-user try)."""

from __future__ import annotations

import json
from types import SimpleNamespace

from plugins.studies import panel_fit


class Pane:
    def __init__(self, pid: str, out: str) -> None:
        self.running = None
        self.fields = {
            "#participant": SimpleNamespace(value=pid),
            "#out": SimpleNamespace(value=out),
        }
        self.said = ("", "information")

    def query_one(self, wid, *_):
        return self.fields[wid]

    def _idle(self) -> None:
        pass


def _run(tmp_path, done: int, total: int = 3) -> None:
    d = tmp_path / "P01"
    d.mkdir()
    (d / "plan.json").write_text(json.dumps({"trials": [{"index": i} for i in range(total)]}))
    lines = [{"event": "start", "trial": i} for i in range(done)]
    lines += [{"event": "done", "trial": i} for i in range(done)]
    (d / "trials.jsonl").write_text("".join(json.dumps(x) + "\n" for x in lines))


def test_a_finished_participant_proposes_the_next(tmp_path):
    _run(tmp_path, done=3)
    pane = Pane("P01", str(tmp_path))
    panel_fit.protocol_changed(pane, "exp1")
    assert pane.said[0] == "P01 has finished exp1 (3/3): s starts P02"
    assert pane.fields["#participant"].value == "P02"


def test_a_run_under_way_says_where_s_resumes(tmp_path):
    _run(tmp_path, done=2)
    pane = Pane("P01", str(tmp_path))
    panel_fit.protocol_changed(pane, "exp1")
    assert pane.said[0] == "protocol exp1: s resumes P01 at trial 3 of 3"


def test_nothing_stored_starts_it(tmp_path):
    pane = Pane("P07", str(tmp_path))
    panel_fit.protocol_changed(pane, "exp1")
    assert pane.said[0] == "protocol exp1 chosen: s starts it with P07"
