"""The whole chain as a user runs it: simulated participants on the twin (the registered
observer, not a double) run by ``study run --simulate``, then ``study analyze`` reads
what the runner wrote."""

from __future__ import annotations

import json

import pytest

SMALL = """
[study]
name = "exp2"
stimulus = "hand_flow"
responses = ["up", "down", "left", "right"]
seed = 5
[[regions]]
name = "Rprelim"
center_mm = [371.73, 223.65]
hand = "right"
[[regions]]
name = "R3"
center_mm = [560.0, 140.0]
hand = "right"
[[regions]]
name = "R4"
center_mm = [580.0, 320.0]
hand = "right"
[[phases]]
name = "preliminary"
factors = { region = ["Rprelim"], direction = ["left", "right"] }
repetitions = 1
replays = "unlimited"
[[phases]]
name = "main"
factors = { region = ["R3", "R4"], direction = ["up", "down", "left", "right"] }
repetitions = 1
block_by = "region"
order = "same_for_all"
replays = 1
"""


@pytest.mark.slow
def test_simulated_run_on_the_twin_then_analyze(tmp_path, capsys):
    from console.cli.main import main

    proto = tmp_path / "exp2-small.toml"
    proto.write_text(SMALL)
    out = tmp_path / "study"
    args = ["study", "run", str(proto), "--simulate", "--participants", "2", "--out", str(out)]
    assert main([*args, "--quiet"]) == 0
    capsys.readouterr()
    part = json.loads((out / "P01" / "participant.json").read_text())
    assert part["simulated"] and part["observer"]["model"] == "plate twin psychophysical observer"
    report = tmp_path / "r.html"
    assert main(["study", "analyze", str(out), "--json", "--report", str(report)]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["participants"] == ["P01", "P02"] and res["simulated"] == ["P01", "P02"]
    acc = res["accuracy"]
    assert [p["trials"] for p in acc["participants"]] == [8, 8]
    assert acc["practice"]["preliminary"] >= 0
    # the ANOVA ran on what the runner wrote (2 participants x 2 regions x 4 directions)
    assert "skipped" not in res["anova"], res["anova"]
    assert {r["source"] for r in res["anova"]["anova"]} == {
        "region",
        "direction",
        "region * direction",
    }
    assert report.read_text().count("data:image/png") == 2
