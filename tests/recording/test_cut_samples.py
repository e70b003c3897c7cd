"""``haptable gestures cut FILE --out DIR`` on a recorded knob demo, as a user runs it:
each recognised gesture becomes a sample the dataset loader reads with its label, a
``--labels`` CSV cuts the user's labels, ``haptable gestures eval`` runs on the cut set,
and bad input is one line."""

from __future__ import annotations

import json

import pytest

# one xdist worker runs this module: its module fixture (a recorded knob demo) computed
# once
pytestmark = pytest.mark.xdist_group("recorded_knob")


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """A 2 s knob demo recorded (the scripted hand turns the knob with two fingers)."""
    from console.cli.main import main
    from console.config import plugins as cp
    from console.config.profile import PROJECT_PROFILES

    mp = pytest.MonkeyPatch()
    for name in ("demos", "recording", "gestures"):
        mp.setitem(cp.BUILTIN_PLUGINS, name, f"plugins.{name}")
    d = tmp_path_factory.mktemp("cut")
    prof = d / "calm.toml"  # a busy test machine must not trip the watchdog
    prof.write_text(
        (PROJECT_PROFILES / "sim.toml").read_text() + "\n[runtime]\nwatchdog_ms = 3000\n"
    )
    path = d / "knob.h5"
    argv = ["--profile", str(prof), "demo", "knob", "--seconds", "2", "--json"]
    assert main([*argv, "--record", str(path)]) == 0
    yield main, path, d
    mp.undo()


def _runs(path):
    """(first seq, last seq, gesture, frames) of each run of one recognised gesture long
    enough to be a sample (2 frames; a dynamic gesture 4), read back."""
    from plugins.gestures.dataset import GESTURES, MIN_FRAMES, kind_of
    from plugins.recording.reader import open_recording

    with open_recording(path) as rec:
        names = [
            (int(rec.seq[k]), (rec.decisions(k)["gesture"] or [None])[0])
            for k in range(rec.n_frames)
        ]
    runs, k = [], 0
    while k < len(names):
        j = k
        while j + 1 < len(names) and names[j + 1][1] == names[k][1]:
            j += 1
        g = names[k][1]
        if g in GESTURES and j - k + 1 >= max(2, MIN_FRAMES[kind_of(g)]):
            runs.append((names[k][0], names[j][0], names[k][1], j - k + 1))
        k = j + 1
    return runs


def test_recognised_gestures_become_samples_the_loader_reads(recorded, capsys):
    from plugins.gestures.dataset import load_dataset

    main, path, d = recorded
    runs = _runs(path)
    assert runs, "the scripted hand was never recognised"
    out = d / "from_decisions"
    capsys.readouterr()
    assert main(["gestures", "cut", str(path), "--out", str(out), "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    samples = load_dataset(out, check_images=True)
    got = sorted(
        (s.meta["start_frame"], s.meta["end_frame"], s.gesture, s.n_frames) for s in samples
    )
    assert got == sorted(runs) and len(res["samples"]) == len(runs)
    assert all(s.background() is not None for s in samples)  # the recorded empty table


def test_a_labels_csv_cuts_the_users_labels_and_eval_runs_on_them(recorded, capsys):
    from plugins.gestures.dataset import load_dataset

    main, path, d = recorded
    seqs = _frames(path, with_hand=True)
    assert len(seqs) >= 8, "the scripted hand was seen on too few frames"
    quarter = len(seqs) // 4
    parts = [seqs[i * quarter : (i + 1) * quarter] for i in range(4)]
    labels = d / "labels.csv"
    rows = ["start_frame,end_frame,gesture"]
    for part, g in zip(
        parts, ("one_finger", "one_finger", "two_finger", "two_finger"), strict=True
    ):
        rows.append(f"{part[0]},{part[-1]},{g}")
    labels.write_text("\n".join(rows) + "\n")
    out = d / "labelled"
    assert main(["gestures", "cut", str(path), "--out", str(out), "--labels", str(labels)]) == 0
    assert "cut 4 samples" in capsys.readouterr().out
    samples = load_dataset(out)
    assert sorted((s.meta["start_frame"], s.gesture) for s in samples) == sorted(
        (p[0], g) for p, g in zip(parts, ("one_finger",) * 2 + ("two_finger",) * 2, strict=True)
    )
    code = main(["gestures", "eval", str(out), "--harmonics", "4", "--frames", "2", "--json"])
    assert code == 0
    rep = json.loads(capsys.readouterr().out)
    assert set(rep["per_class_recall"]) == {"one_finger", "two_finger"}


def _frames(path, with_hand=False):
    """The recorded frame numbers (``with_hand``: of the frames where a hand was seen)."""
    from plugins.recording.reader import open_recording

    with open_recording(path) as rec:
        keep = [not with_hand or bool(rec.decisions(k)["hands"]) for k in range(rec.n_frames)]
        return [int(s) for s, ok in zip(rec.seq, keep, strict=True) if ok]


@pytest.mark.parametrize(
    ("line", "says"),
    [
        ("{a},9999999,one_finger", "frame 9999999 is not in the recording"),
        ("{a},{b},pinch", "gesture 'pinch': use one of"),
        ("{a},{b}", "give start_frame,end_frame,gesture"),
    ],
)
def test_bad_labels_and_files_are_one_line(recorded, capsys, line, says):
    main, path, d = recorded
    seqs = _frames(path)
    labels = d / "bad.csv"
    labels.write_text(line.format(a=seqs[0], b=seqs[5]) + "\n")
    assert main(["gestures", "cut", str(path), "--out", str(d / "x"), "--labels", str(labels)]) == 2
    err = capsys.readouterr().err.strip()
    assert says in err and str(labels) in err and "line 1" in err and "\n" not in err
    assert main(["gestures", "cut", str(d / "none.h5"), "--out", str(d / "x")]) == 2
    err = capsys.readouterr().err.strip()
    assert "none.h5: no such file" in err and "\n" not in err
