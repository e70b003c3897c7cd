"""The core commands as a user runs them."""

from __future__ import annotations

import json
import os
import re
import time

from console.cli.main import main
from console.runtime.control import send_command


def test_doctor_json_reports_each_device(capsys):
    assert main(["doctor", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    rt = {d["name"]: d for d in data["devices"] if d["kind"] == "realtime"}
    kinds = {d["kind"]: d for d in data["devices"] if d["kind"] != "realtime"}
    assert set(kinds) == {"audio", "relays", "camera", "vibrometer", "gestures"}
    assert kinds.pop("gestures")["state"] == "ok"  # no touch calibration yet: pixels
    assert all(d["state"] == "simulated" for d in kinds.values()) and data["ok"]
    assert set(rt) == {"memory", "scheduling"}
    assert all(d["state"] == "ok" for d in rt.values())  # the twin plays without (it says so)


def test_doctor_names_the_memory_lock_fix_for_a_sound_card(monkeypatch, plugins):
    from console.config.profile import load_profile
    from console.kernel import memory_lock
    from console.runtime import doctor

    monkeypatch.setattr(memory_lock, "_may_lock", lambda: (False, "memlock limit 8192 kB"))
    prof = load_profile("haptable-lab", plugins)
    st = doctor.realtime_status(prof, plugins)
    assert st.state == "missing" and "8192 kB" in st.why and "memlock unlimited" in st.fix


def test_doctor_names_the_realtime_fix_for_a_sound_card(monkeypatch, plugins):
    from console.config.profile import load_profile
    from console.core import realtime
    from console.runtime import doctor

    monkeypatch.setattr(realtime, "realtime_priority", lambda above_min=10: False)
    prof = load_profile("haptable-lab", plugins)
    st = doctor.scheduling_status(prof, plugins)
    assert st.state == "missing" and "rtprio 95" in st.fix
    assert doctor.scheduling_status(load_profile("sim", plugins), plugins).state == "ok"


def test_doctor_on_lab_profile_says_what_is_missing_and_the_fix(capsys):
    code = main(["--profile", "haptable-lab", "doctor", "--json"])
    data = json.loads(capsys.readouterr().out)
    relays = next(d for d in data["devices"] if d["kind"] == "relays")
    if relays["state"] in ("missing", "error"):
        assert code == 1 and relays["fix"]


def test_play_named_stimulus_reports_relay_switches(capsys):
    assert main(["play", "relay-walk", "--fast"]) == 0
    out = capsys.readouterr().out
    assert "played relay-walk" in out
    switches = [ln for ln in out.splitlines() if ln.strip().startswith("relay ")]
    assert len(switches) == 14  # PA, PB, PC, PD one by one, then PALL, each closed and opened
    assert all("(outputs 0.0 V / 0.0 V)" in ln for ln in switches)


def test_play_unknown_stimulus_one_line(capsys):
    assert main(["play", "sine-PE"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "sine-PE" in err and "sine-PA" in err


def test_play_writes_wav(tmp_path, capsys):
    import wave

    path = tmp_path / "s.wav"
    assert main(["play", "screen-180hz", "--dry-run", "--out", str(path)]) == 0
    with wave.open(str(path)) as w:
        assert w.getnchannels() == 2 and w.getframerate() == 48000 and w.getnframes() == 48000


def test_estop_reaches_a_running_console(plugins, capsys):
    """`haptable estop` e-stops the table's kernel; the console, a client of it, hears it
    from there (its screens stop what they run) and is named among the table's users."""
    from console.runtime.context import Context
    from console.session.core import ConsoleSession
    from console.session.events import Stopped

    session = ConsoleSession(Context("sim", plugins), fast=False)  # the profile's table
    seen = []
    session.subscribe(seen.append)
    try:
        assert session.open_outputs(), session.outputs_error
        assert send_command(session.profile, "ping") == "pong"  # the console runs
        kernel_pid = session.outputs.kernel_pid
        assert main(["estop", "--json"]) == 0
        data = json.loads(capsys.readouterr().out)
        t_end = time.monotonic() + 5
        while not any(isinstance(e, Stopped) and e.topic == "estop" for e in seen):
            assert time.monotonic() < t_end, seen
            time.sleep(0.01)
        estopped = session.outputs.estopped
        reason = session.outputs.estop_reason
    finally:
        session.close()
    reached = [t for t in data["tables"] if t["pid"] == kernel_pid]
    assert reached and reached[0]["confirmed"] and data["confirmed"], data
    assert any(f"(pid {os.getpid()})" in c for c in reached[0]["clients"]), reached
    assert estopped and "haptable estop" in reason


def test_estop_without_console(capsys):
    assert main(["estop"]) == 0
    out = capsys.readouterr().out
    assert "no outputs open" in out and "latched until an operator resets it" in out


def test_an_output_path_that_cannot_be_written_is_one_line(capsys):
    """A file the command must write into a place that cannot hold it: one line, exit 2."""
    from console.cli.main import main

    assert main(["play", "sine-PA", "--dry-run", "--out", "/dev/null/x.wav"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "/dev/null/x.wav" in err[0] and "internal error" not in err[0]


def test_bench_list_names_every_benchmark_in_a_column(capsys, monkeypatch):
    from console.cli import core_commands
    from console.config.plugins import load_plugins

    monkeypatch.setenv("COLUMNS", "80")
    assert main(["bench", "list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    names = sorted(load_plugins(core=core_commands).benchmarks)
    assert {"safety", "vibration", "console"} <= set(names)
    firsts = [line for line in lines if not line[0].isspace()]  # a description wraps
    assert [line.split()[0] for line in firsts] == names
    assert all(len(line) <= 80 for line in lines)
    col = {re.match(r"\S+\s+", line).end() for line in firsts}  # descriptions in one column
    col |= {len(line) - len(line.lstrip()) for line in lines if line[0].isspace()}
    assert len(col) == 1
    assert main(["bench"]) == 0  # no name: the same list
    assert capsys.readouterr().out.splitlines() == lines
    assert main(["bench", "list", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in rows] == names and all(r["help"] for r in rows)
