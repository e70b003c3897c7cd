"""`haptable gestures synth` says the size and time before it starts (measured on one
sample of each kind), `--dry-run` only says it; the estimate's size against the set's."""

from __future__ import annotations

import json

from console.cli.main import main
from plugins.gestures.synth import estimate, synth


def test_cli_synth_says_size_and_time_first(tmp_path, capsys):
    out = tmp_path / "set"
    args = ["gestures", "synth", "--subjects", "1", "--reps", "1", "--workers", "1"]
    args += ["--gestures", "one_finger,drag", "--out", str(out)]
    assert main([*args, "--dry-run"]) == 0
    said = capsys.readouterr()
    assert said.out.startswith("would write 1 x 2 x 1 = 2 samples (16 images): about ")
    assert " MB and " in said.out and "per image" in said.out
    assert not out.exists()

    assert main(args) == 0
    said = capsys.readouterr()
    first = said.err.splitlines()[0]
    assert first.startswith("writing 1 x 2 x 1 = 2 samples (16 images): about "), said.err
    assert "wrote 2 samples (14 frames, " in said.out and " MB) to " in said.out

    assert main([*args[:-1], str(tmp_path / "j"), "--dry-run", "--json"]) == 0
    est = json.loads(capsys.readouterr().out)
    assert est["samples"] == 2 and est["images"] == 16 and est["bytes"] > 0


def test_estimated_size_is_the_written_size(tmp_path):
    kw = {"workers": 1, "gestures": ("one_finger", "l_shape", "drag", "wipe")}
    est = estimate(2, 2, **kw)
    info = synth(tmp_path / "set", 2, 2, **kw)
    written = sum(p.stat().st_size for p in (tmp_path / "set").rglob("*.png"))
    assert est["samples"] == info["samples"] == 16
    assert abs(est["bytes"] - written) < 0.1 * written
