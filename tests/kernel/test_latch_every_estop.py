"""Every e-stop that latches a table is recorded, and `haptable reset` says each one it
clears (new operator's try: two `haptable estop` in a row, then `haptable reset` named
only the first). The first stays the cause; the later ones follow, bounded. A latch file
of one record (as written before) still loads. `haptable estop` names each table it
latched with the exact command that resets it."""

from __future__ import annotations

import json
import subprocess
import sys

from console.files.profile_paths import known_profiles
from console.kernel.tables import (
    MAX_LATCH_BYTES,
    describe_latch,
    latch_record,
    read_latch,
    table_for,
    write_latch,
)

from .test_kernel import ROOT, _env, at_terminal, haptable


def _estop_pid() -> int:
    """Run `haptable estop` from a shell; its pid (the latch's reason names it)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "console.cli.entry", "estop"],
        cwd=ROOT,
        env=_env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, out + err
    return proc.pid


def _reset_line(text: str, name: str) -> str:
    lines = [ln for ln in text.splitlines() if ln.startswith(f"reset: table {name}:")]
    assert len(lines) == 1, text
    return lines[0]


def test_reset_reports_both_of_two_shell_estops_with_no_kernel_running(profile):
    first, second = _estop_pid(), _estop_pid()
    code, text = at_terminal("--profile", "sim", "reset")
    assert code == 0, text
    line = _reset_line(text, "sim")
    assert "was: 2 e-stops:" in line, line
    assert line.index(f"haptable estop (pid {first},") < line.index(
        f"haptable estop (pid {second},"
    ), line
    assert read_latch(table_for(profile.path)) is None


def test_the_console_path_reports_both_of_two_shell_estops_of_a_running_table(profile, plugins):
    """Through the running kernel (what ctrl+r reaches): both e-stops, each once, though
    the kernel latches the same e-stop again when it reaches it and when its gate says so."""
    from console.kernel.client import open_outputs

    out = open_outputs(profile, plugins, fast=True, private=False)
    try:
        first, second = _estop_pid(), _estop_pid()
        assert out.wait_safe(5)
        latched = read_latch(out.table)
        assert latched is not None and latched["reason"].startswith(
            f"haptable estop (pid {first},"
        ), latched  # the first stays the cause
        code, text = at_terminal("--profile", "sim", "reset")
    finally:
        out.close()
    assert code == 0, text
    line = _reset_line(text, "sim")
    assert "was: 2 e-stops:" in line, line
    assert line.count("haptable estop (pid ") == 2, line
    assert f"(pid {first}," in line and f"(pid {second}," in line, line


def test_an_old_single_record_latch_file_still_loads_and_is_added_to(profile):
    table = table_for(profile.path).ensure()
    old = {  # the whole of a latch file as written before later e-stops were kept
        "reason": "haptable estop (pid 4242, alice on /dev/pts/3)",
        "by": "haptable estop",
        "pid": 4242,
        "t": 1795000000.0,
        "time": "2026-11-18 10:00:01",
    }
    table.latch_path.write_text(json.dumps(old))
    assert read_latch(table) == old
    assert (
        describe_latch(old)
        == "haptable estop (pid 4242, alice on /dev/pts/3) at 2026-11-18 10:00:01"
    )
    write_latch(table, latch_record("operator e-stop (console)", "the console"))
    latched = read_latch(table)
    assert latched["reason"] == old["reason"] and latched["time"] == old["time"]
    code, text = at_terminal("--profile", "sim", "reset")
    assert code == 0, text
    line = _reset_line(text, "sim")
    assert (
        "was: 2 e-stops: haptable estop (pid 4242, alice on /dev/pts/3) at 2026-11-18 10:00:01; operator e-stop (console) at "
        in line
    ), line


def test_many_estops_keep_the_first_and_the_latest_and_the_file_stays_readable(profile):
    table = table_for(profile.path)
    long = "é" * 400  # the longest reason kept, as \\u escapes in the file
    for i in range(40):
        write_latch(table, latch_record(f"e-stop {i} {long}", f"source {i}"))
    assert table.latch_path.stat().st_size <= MAX_LATCH_BYTES
    latched = read_latch(table)
    assert latched["reason"].startswith("e-stop 0 ")  # the cause
    said = describe_latch(latched)
    assert said.startswith("40 e-stops: e-stop 0 "), said[:80]
    assert "e-stop 39 " in said and "e-stop 1 " not in said, said
    kept = said.count("; e-stop ") + 1
    assert f"({40 - kept} not kept)" in said, said


def test_estop_names_each_table_and_the_command_that_resets_it():
    got = haptable("estop")
    assert got.returncode == 0, got.stdout + got.stderr
    names = sorted(known_profiles())
    assert len(names) >= 3, names
    for name in names:
        lines = [ln for ln in got.stdout.splitlines() if f"table {name} latched" in ln]
        assert len(lines) == 1, got.stdout
        assert f"`haptable --profile {name} reset`" in lines[0], lines[0]
    # the command it names resets that table, and only that one
    code, text = at_terminal("--profile", "sim-4ch", "reset")
    assert code == 0 and "reset: table sim-4ch: e-stop reset by" in text, text
    assert read_latch(table_for(known_profiles()["sim-4ch"])) is None
    assert read_latch(table_for(known_profiles()["sim"])) is not None


def test_estop_of_one_profile_says_its_own_reset_command():
    got = haptable("--profile", "sim-4ch", "estop")
    assert got.returncode == 0, got.stdout + got.stderr
    latched = [ln for ln in got.stdout.splitlines() if "latched" in ln and "table" in ln]
    assert latched == [
        "e-stop: table sim-4ch latched until an operator resets it: `haptable --profile sim-4ch reset`"
    ], got.stdout
