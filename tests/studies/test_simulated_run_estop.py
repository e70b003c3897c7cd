"""A new user's trial: a simulated study run in a shell plays on a private fast twin of
the table, and the console's ctrl+e (the table's e-stop) did not stop it: it played trials
29..50, said 'finished' and exited 0. The e-stop always wins: a shell study run on a table,
simulated or not, stops at the table's e-stop (the console's ctrl+e or `haptable
estop`), exits 4 saying which trial was stopped and how to resume, and a latched table
refuses it as it refuses a real run; the console names it as the simulated run it is."""

from __future__ import annotations

import asyncio
import json
import os
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from console.cli.main import Context
from console.config.profile import load_profile
from console.kernel.tables import clear_latch, read_latch, table_for
from console.runtime.map_hold import map_holder
from console.tui.app import HapTableApp

from .studies_pilot import wait_for

ROOT = Path(__file__).resolve().parents[2]
#: the exit status of a command the e-stop stopped (README, Commands)
EXIT_ESTOPPED = 4


class _Run:
    """``haptable study run exp1 --participant P03 --simulate`` in a shell."""

    def __init__(self, out: Path, *more: str) -> None:
        args = ["study", "run", "exp1", "--participant", "P03", "--out", str(out), "--simulate"]
        args += more
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "console.cli.entry", *args],
            cwd=ROOT,
            env={**os.environ, "PYTHONPATH": str(ROOT)},
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.out: list[str] = []
        self.err = ""
        self._t = threading.Thread(target=self._read, daemon=True)
        self._t.start()

    def _read(self) -> None:
        for line in self.proc.stdout:
            self.out.append(line.rstrip("\n"))

    def done_trials(self) -> int:
        return sum(1 for ln in self.out if ln.startswith("  P03 trial ") and "/50" in ln)

    def wait_trials(self, n: int, timeout_s: float = 90.0) -> None:
        t_end = time.monotonic() + timeout_s
        while time.monotonic() < t_end:
            if self.done_trials() >= n:
                return
            assert self.proc.poll() is None, f"exited {self.proc.returncode}: {self.out[-3:]}"
            time.sleep(0.05)
        raise AssertionError(f"{n} trials not done in {timeout_s:g} s: {self.out[-3:]}")

    def finish(self, timeout_s: float = 30.0) -> int:
        try:
            code = self.proc.wait(timeout_s)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()
        self._t.join(5)
        if not self.proc.stderr.closed:
            self.err = self.proc.stderr.read()
            self.proc.stderr.close()
        return code


def _haptable(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "console.cli.entry", *args],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        timeout=60,
    )


def _stopped_as_said(run: _Run, code: int, out: Path) -> int:
    """The run exited 4 naming the trial stopped and how to resume; that trial is marked
    interrupted (it runs again). Returns the trial's number."""
    assert code == EXIT_ESTOPPED, (code, run.out[-3:], run.err)
    assert not any("(finished)" in ln for ln in run.out), run.out[-3:]
    said = [ln for ln in run.out if "stopped by the e-stop" in ln]
    assert said, run.out[-3:]
    n = int(said[-1].split("trial ")[1].split()[0])
    assert n <= 50 and run.done_trials() == n - 1, (n, run.out[-3:])
    assert "ctrl+r in the console" in said[-1] and f"resumes at trial {n}" in said[-1]
    assert "haptable: e-stopped by " in run.err, run.err
    events = [json.loads(ln) for ln in (out / "P03" / "trials.jsonl").read_text().splitlines()]
    assert not [e for e in events if e.get("event") == "done" and e["trial"] >= n - 1], n
    return n


def test_a_shell_estop_stops_a_simulated_run_and_the_latch_refuses_the_next(plugins, tmp_path):
    run = _Run(tmp_path / "runs")
    try:
        run.wait_trials(5)
        got = _haptable("--profile", "sim", "estop")
        assert got.returncode == 0, got.stdout + got.stderr
        # the shell's e-stop names the run it reached
        assert "haptable study run exp1" in got.stdout, got.stdout
        code = run.finish()
    finally:
        run.finish(1)
    n = _stopped_as_said(run, code, tmp_path / "runs")
    # latched: the same command is refused as a real run is, nothing played
    again = _Run(tmp_path / "runs")
    assert again.finish(60) == EXIT_ESTOPPED, again.out[-3:]
    assert "e-stop latched" in again.err and "ctrl+r in the console" in again.err, again.err
    assert again.done_trials() == 0, again.out
    # once reset (the operator's; here its latch cleared), it resumes where it said
    clear_latch(table_for(load_profile("sim", plugins).path))
    resumed = _Run(tmp_path / "runs", "--trials", "1")
    assert resumed.finish(60) == 0, (resumed.out[-3:], resumed.err)
    assert f"P03: resuming at trial {n} of 50" in "\n".join(resumed.out), resumed.out[:3]


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_the_console_s_ctrl_e_stops_a_shell_s_simulated_run(plugins, tmp_path, size):
    profile = load_profile("sim", plugins)
    run = _Run(tmp_path / "runs")

    async def scenario() -> None:
        app = HapTableApp(Context("sim", plugins), fast=False, initial="vibration")
        async with app.run_test(size=size, notifications=True) as pilot:
            await wait_for(pilot, lambda: app.query("#vib-status"), what="its status")
            await wait_for(pilot, lambda: map_holder(profile) is not None, 60, "the run's hold")
            await pilot.pause(0.5)
            await pilot.press("m")

            def status() -> str:
                return " ".join(str(app.query_one("#vib-status").render()).split())

            await wait_for(pilot, lambda: "refused" in status(), 10, "the refusal")
            # named as what it is: a simulated run, which the e-stop stops
            assert status().startswith(
                "measure refused: a simulated study run of exp1 (haptable study run "
                "--simulate, pid "
            ), status()
            await asyncio.to_thread(run.wait_trials, 5)
            await pilot.press("ctrl+e")
            await wait_for(pilot, lambda: run.proc.poll() is not None, 30, "the run's end")
            assert read_latch(table_for(profile.path)) is not None

    try:
        asyncio.run(scenario())
        code = run.finish()
    finally:
        run.finish(1)
    _stopped_as_said(run, code, tmp_path / "runs")
    assert "operator e-stop (console)" in run.err, run.err


def test_a_shell_estop_stops_a_simulated_adaptive_run_saying_where_it_resumes(tmp_path):
    out = tmp_path / "thr"
    args = ["study", "run", "threshold_electrovibration", "--participant", "P01"]
    args += ["--out", str(out), "--simulate"]
    proc = subprocess.Popen(
        [sys.executable, "-m", "console.cli.entry", *args],
        cwd=ROOT,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True)
    reader.start()
    try:
        t_end = time.monotonic() + 90
        while sum(ln.startswith("  P01 trial ") for ln in list(lines)) < 3:
            assert proc.poll() is None and time.monotonic() < t_end, lines[-3:]
            time.sleep(0.05)
        assert _haptable("--profile", "sim", "estop").returncode == 0
        code = proc.wait(30)
    finally:
        if proc.poll() is None:
            proc.kill()
        proc.wait()
    reader.join(5)
    err = proc.stderr.read()
    assert code == EXIT_ESTOPPED, (code, lines[-3:], err)
    said = [ln for ln in lines if "stopped by the e-stop" in ln]
    assert said and "the same command resumes at trial " in said[-1], lines[-3:]
    assert "haptable: e-stopped by haptable estop" in err, err
