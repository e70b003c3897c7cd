"""``haptable signals`` as a user runs it: list, show, add, play through the gate, rm."""

from __future__ import annotations

import json

import numpy as np
import pytest

from console.cli.main import main
from console.config.signal_library import library_path

PULSE = "seq(sine(250 Hz, 40 V, 0.5 s) * adsr(10 ms, 50 ms, 0.7, 100 ms), silence(0.2 s)) * 3"


def test_list_show_add_rm(capsys):
    assert main(["signals", "list"]) == 0
    out = capsys.readouterr().out
    assert "sweep" in out and "[built-in]" in out and "none saved yet" in out
    assert main(["signals", "add", "pulse", PULSE, "--description", "three pulses"]) == 0
    assert library_path("sim").exists()
    capsys.readouterr()
    assert main(["signals", "list", "--json"]) == 0
    rows = {r["name"]: r for r in json.loads(capsys.readouterr().out)["signals"]}
    assert rows["pulse"] == {
        "name": "pulse",
        "expr": PULSE,
        "description": "three pulses",
        "builtin": False,
        "target": "",  # meant for no channel: --patch or --screen says where it plays
    }
    assert main(["signals", "show", "pulse"]) == 0
    out = capsys.readouterr().out
    assert "duration 2.100 s" in out and "peak     39.7" in out and "dominant 250.0 Hz" in out
    assert main(["signals", "show", "sine(100 Hz, 10 V, 1 s)", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["rms_v"] == pytest.approx(10 / np.sqrt(2), rel=1e-4)
    assert main(["signals", "rm", "pulse"]) == 0
    assert main(["signals", "show", "pulse"]) == 2
    assert "no signal 'pulse'" in capsys.readouterr().err


def test_play_on_patches_and_screen_reaches_the_twin(capsys, tmp_path, monkeypatch):
    log = tmp_path / "twin.json"
    monkeypatch.setenv("HAPTABLE_TWIN_LOG", str(log))
    assert main(["signals", "add", "pulse", PULSE]) == 0
    assert main(["signals", "play", "pulse", "--patch", "PA,PC", "--fast"]) == 0
    out = capsys.readouterr().out
    assert "played pulse: 2.10 s" in out
    closed = [ln for ln in out.splitlines() if "closed" in ln]
    assert len(closed) == 2 and "relay 1 " in closed[0] and "relay 3 " in closed[1]
    rec = np.load(log.with_suffix(".npz"))["recording_v"]
    assert np.max(np.abs(rec[:, 0])) == pytest.approx(39.7, abs=0.1) and not rec[:, 1].any()
    assert main(["signals", "play", "screen-180", "--screen", "--fast"]) == 0
    rec = np.load(log.with_suffix(".npz"))["recording_v"]
    assert np.max(np.abs(rec[:, 1])) == pytest.approx(50.0, rel=1e-3) and not rec[:, 0].any()


@pytest.mark.parametrize(
    ("argv", "says"),
    [
        (["play", "sine(250 Hz, 40 V, 1 s)", "--screen"], "multiply it by ramp(5 ms)"),
        (["play", "tone-250", "--patch", "PE"], "unknown patch 'PE'"),
        (["play", "sine(250 Hz, 400 V, 1 s) * ramp(10 ms)", "--patch", "PA"], "piezo range"),
        (["add", "x", "sine(250, 4 V, 1 s)"], "needs a unit"),
        (["add", "sweep", "silence(1 s)"], "built-in"),
        (["show", "swep"], "did you mean 'sweep'"),
    ],
)
def test_errors_are_one_line(capsys, argv, says):
    assert main(["signals", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert says in err and err.startswith("haptable: error:") and "\n" not in err


def test_signals_benchmark_reports_timing_and_accuracy(capsys):
    assert main(["bench", "signals", "--quick", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert set(data["timing"]["tone 1 s"]) == {"parse", "render", "gate_check"}
    assert data["timing"]["60 s tone"]["render"]["n"] == 5
    acc = data["accuracy"]
    assert acc["sine_freq_err_hz"] < 0.1 and acc["chirp_inst_freq_rel_err"] < 0.01
    assert acc["sine_vs_tone_max_abs_v"] < 1e-9 and acc["adsr_level_err"] < 1e-9
