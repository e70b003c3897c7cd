"""``haptable study analyze --exclude ID``: an id no participant has is refused in one
line naming it and the participants there (exit 2), not accepted silently."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import synth_runs as sr  # noqa: E402


def _cli(*args):
    from console.cli.main import main

    return main(["study", "analyze", *map(str, args)])


def test_exclude_of_an_unknown_participant_is_refused(tmp_path, capsys):
    root = sr.write_flow(tmp_path / "e", "exp1", ("1", "2"), lambda *a: 0.9, 3, 2)
    assert _cli(root, "--exclude", "P09") == 2
    cap = capsys.readouterr()
    assert cap.out == ""
    err = cap.err.strip()
    assert "\n" not in err and "P09" in err and "--exclude" in err
    assert "P01, P02, P03" in err
    # a participant that exists is still left out
    assert _cli(root, "--exclude", "P02") == 0
    assert "P02: left out (--exclude)" in capsys.readouterr().out
