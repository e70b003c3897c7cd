"""``haptable demo knob --record FILE`` then ``haptable replay FILE``, as a user runs them:
the same decisions; one frame changed in the file: the first difference names it.
(The flow demo needs its measured map and plan atlas, minutes in a fresh cache: its record
and replay, plans compared, run by hand: ``haptable demo flow --record F; haptable replay F``.)"""

from __future__ import annotations

import shutil

import numpy as np
import pytest


@pytest.fixture
def cli(monkeypatch):
    from console.config import plugins as cp

    for name in ("demos", "recording"):
        monkeypatch.setitem(cp.BUILTIN_PLUGINS, name, f"plugins.{name}")
    from console.cli.main import main

    return main


def test_a_recorded_demo_replays_the_same_and_a_tampered_frame_is_named(cli, capsys, tmp_path):
    import h5py

    from console.config.profile import PROJECT_PROFILES
    from plugins.recording.reader import open_recording

    prof = tmp_path / "calm.toml"  # a busy test machine must not trip the watchdog
    prof.write_text(
        (PROJECT_PROFILES / "sim.toml").read_text() + "\n[runtime]\nwatchdog_ms = 3000\n"
    )
    path = tmp_path / "knob.h5"
    argv = ["--profile", str(prof), "demo", "knob", "--seconds", "2", "--json"]
    assert cli([*argv, "--record", str(path)]) == 0
    capsys.readouterr()
    with open_recording(path) as rec:
        n, hands = rec.n_frames, [k for k in range(rec.n_frames) if rec.decisions(k)["hands"]]
        assert rec.attrs["demo"] == "knob" and rec.stats["dropped"] == 0
        assert "[camera]" in rec.attrs["profile_toml"] and rec.background() is not None
        assert rec.scene(rec.n_frames - 1)["kind"] == "knob"  # the projected scene's state
        seq = int(rec.seq[hands[len(hands) // 2]])
        streams = [p for p in rec.plans() if p["kind"] == "stream"]
        assert streams and streams[0]["name"].startswith("knob")  # the knob's live stream
    assert n > 20 and len(hands) > 5  # the scripted hand turned the knob

    assert cli(["--profile", str(prof), "replay", str(path)]) == 0  # through the knob demo
    out = capsys.readouterr().out.strip()
    assert out.startswith(f"replay: {n} frames,") and "the same (knob demo); " in out
    assert out.endswith(" recorded") and "gate event" in out  # the kernel's own events

    bad = tmp_path / "tampered.h5"
    shutil.copy(path, bad)
    with h5py.File(bad, "r+") as f:  # one frame with a hand: the empty table instead
        k = int(np.flatnonzero(f["seq"][:] == seq)[0])
        f["frames"][k] = np.clip(f["background"][()], 0, 255).astype(np.uint8)
    assert cli(["--profile", str(prof), "replay", "--vision-only", str(bad)]) == 1
    out = capsys.readouterr().out.strip()
    assert out.startswith(f"replay: first difference at frame {seq}: ") and "\n" not in out


def test_replay_and_record_refuse_bad_paths_in_one_line(cli, capsys, tmp_path):
    assert cli(["replay", str(tmp_path / "none.h5")]) == 2
    err = capsys.readouterr().err.strip()
    assert str(tmp_path / "none.h5") in err and "no such file" in err and "\n" not in err
    target = tmp_path / "no" / "run.h5"
    assert cli(["demo", "knob", "--seconds", "1", "--record", str(target)]) == 2
    err = capsys.readouterr().err.strip()
    assert str(target.parent) in err and "create it" in err and "\n" not in err
