"""Issue 27: a demo started from a shell (``haptable demo knob``, profile sim) plays on the
table as a shell's study run does, yet the console played over it: Vibration's Enter,
Devices' ``t``, Electrostatic's ``p``, Signals' ``ctrl+o`` and a relay's toggle went to
the outputs. The demo holds the table as the study run does (one hold file, one check in
the console): each is refused at once naming the demo, its pid and that ctrl+c in its
shell stops it; the hold goes with the demo whatever ends it (its end, ctrl+c, the
e-stop, a kill), and another shell's ``haptable play`` meanwhile is busy (exit 5)."""

from __future__ import annotations

import asyncio
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from textual.widgets import Input

from console.cli.main import Context
from console.config.profile import load_profile
from console.runtime.measured_map import measured_map
from console.runtime.table_hold import table_hold_file, table_holder
from console.tui.app import HapTableApp

from ..kernel.test_kernel import at_terminal, haptable
from ..tui.conftest import wait_for, words_on

ROOT = Path(__file__).resolve().parents[2]


def _shell(*args: str) -> subprocess.Popen:
    """``haptable ARGS`` typed at a shell (Ctrl-C reaches it as it reaches a command
    typed at a terminal, whatever the test worker does with SIGINT)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen(
        [sys.executable, "-m", "console.cli.entry", *args],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )


def _held(profile, proc: subprocess.Popen, timeout_s: float = 90.0) -> str:
    t_end = time.monotonic() + timeout_s
    while time.monotonic() < t_end and proc.poll() is None:
        who = table_holder(profile)
        if who is not None:
            return who
        time.sleep(0.05)
    err = proc.stderr.read() if proc.poll() is not None and proc.stderr else ""
    raise AssertionError(f"the shell's command held no table (exit {proc.poll()}): {err}")


def _ended(proc: subprocess.Popen, timeout_s: float = 30.0) -> int:
    code = proc.wait(timeout_s)
    if proc.stderr:
        proc.stderr.close()
    return code


def _ended_said(proc: subprocess.Popen, timeout_s: float = 30.0) -> tuple[int, str]:
    """(exit status, what it wrote to stderr)."""
    code = proc.wait(timeout_s)
    return code, proc.stderr.read() if proc.stderr else ""


@pytest.mark.parametrize("size", [(80, 24), (120, 40)])
def test_a_shell_s_demo_holds_the_console_s_plays(plugins, size):
    profile = load_profile("sim", plugins)
    measured_map(profile, plugins)  # the twin's map kept: Vibration opens with it
    proc = _shell("demo", "knob", "--seconds", "0")
    try:
        who = _held(profile, proc)
        assert who == f"the knob demo (haptable demo knob, pid {proc.pid})", who
        busy = haptable("play", "sine-PA")  # another shell: busy, naming the demo
        assert busy.returncode == 5, busy.stderr
        assert f"{who} holds the outputs" in busy.stderr, busy.stderr

        async def scenario():
            app = HapTableApp(Context("sim", plugins), fast=True, initial="vibration")
            async with app.run_test(size=size) as pilot:
                await wait_for(pilot, lambda: app.session.outputs is not None, 30, "outputs")
                await wait_for(
                    pilot, lambda: "kept measurement" in words_on(app, "#vib-status"), 30
                )
                refused = f"refused: {who} holds the outputs (ctrl+c in its shell stops it)"

                async def says(selector: str, what: str) -> None:
                    await wait_for(pilot, lambda: refused in words_on(app, selector), 5, what)

                await pilot.press("enter")  # F3: a point's audition
                await says("#vib-status", "Enter on Vibration")
                await pilot.press("f1")
                await wait_for(pilot, lambda: app.pane("devices") is not None, 20, "F1")
                devices = app.pane("devices")
                await wait_for(pilot, lambda: app.focused is not None, 10, "focus")
                await pilot.press("t")  # F1: the test signal
                await wait_for(pilot, lambda: refused in " ".join(devices.result.split()), 5)
                await pilot.press("f5")
                await wait_for(pilot, lambda: app.query("#es-status"), 30, "F5")
                await pilot.pause(0.3)
                await pilot.press("p")  # F5: the setting
                await says("#es-status", "p on Electrostatic")
                await pilot.press("f8")
                signals = app.pane("signals")
                await wait_for(pilot, lambda: signals and bool(signals.entries), 20, "F8")
                app.query_one("#sig-expr", Input).value = "sine(250 Hz, 20 V, 0.5 s)"
                app.query_one("#sig-name", Input).value = ""
                await pilot.press("ctrl+o")  # F8: the designed signal
                await says("#sig-status", "ctrl+o on Signals")
                await pilot.press("f4")
                await wait_for(pilot, lambda: app.pane("relays") is not None, 20, "F4")
                await pilot.pause(0.3)
                await pilot.press("2")  # F4: a relay's toggle
                row = app.query_one("#interlock-2")
                await wait_for(pilot, lambda: "refused" in str(row.render()), 5, "2 refused")
                assert who in " ".join(str(row.render()).split())
                assert not app.session.played  # nothing reached the outputs
                assert 2 not in app.session.outputs.operator_relays()
                proc.send_signal(signal.SIGINT)  # ctrl+c in its shell: the hold goes
                code, err = await asyncio.to_thread(_ended_said, proc)
                # 0; or 4 when the demo's own watchdog e-stopped it first (a loaded machine)
                assert code == 0 or (code == 4 and "e-stop" in err), (code, err)
                assert table_holder(profile) is None

        asyncio.run(scenario())
    finally:
        if proc.poll() is None:
            proc.send_signal(signal.SIGINT)
            _ended(proc)


def test_the_hold_goes_with_the_demo_however_it_ends(plugins):
    profile = load_profile("sim", plugins)
    path = table_hold_file(profile)
    ended = _shell("demo", "flow", "--seconds", "2")  # its own end
    _held(profile, ended)
    assert _ended(ended, 90) == 0 and not path.exists()
    stopped = _shell("demo", "knob", "--seconds", "0")  # the e-stop from another shell
    try:
        _held(profile, stopped)
        assert haptable("estop").returncode == 0
        assert _ended(stopped) == 4 and not path.exists()
    finally:
        if stopped.poll() is None:
            stopped.kill()
            _ended(stopped)
    assert at_terminal("reset")[0] == 0  # an operator's reset
    killed = _shell("demo", "knob", "--seconds", "0")  # a crash: its file holds nothing
    _held(profile, killed)
    killed.kill()
    _ended(killed)
    assert path.exists() and table_holder(profile) is None
    again = haptable("play", "sine-PA")
    assert again.returncode == 0, again.stderr


def test_a_hold_whose_pid_went_to_another_process_holds_nothing(plugins, tmp_path):
    profile = load_profile("sim", plugins)
    path = table_hold_file(profile)
    other = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        # written by a holder that died, its pid now another process's (started later)
        hold = {"pid": other.pid, "who": "the knob demo (pid X)", "started": "1"}
        path.write_text(json.dumps(hold), encoding="utf-8")
        assert table_holder(profile) is None
        hold.pop("started")  # an older file, no start time: a live pid holds it
        path.write_text(json.dumps(hold), encoding="utf-8")
        assert table_holder(profile) == "the knob demo (pid X)"
    finally:
        other.kill()
        other.wait()


def test_a_long_play_holds_the_table_a_short_one_does_not(plugins):
    """A short play is over before a console key waiting for it is missed (Relays says
    which play a toggle waits for); a long one is refused at once in the console as a
    demo is, naming it."""
    profile = load_profile("sim", plugins)
    expr = "sine(250 Hz, 10 V, 8 s) * ramp(20 ms)"
    long_ = _shell("signals", "play", expr, "--patch", "PA")
    try:
        who = _held(profile, long_)
        assert who.startswith("haptable signals play sine(250 Hz") and f"(pid {long_.pid})" in who
        session_said = _console_refusal(plugins)
        assert f"refused: {who} holds the outputs (ctrl+c in its shell stops it)" in session_said
        long_.send_signal(signal.SIGINT)
        _ended(long_)
        assert table_holder(profile) is None
    finally:
        if long_.poll() is None:
            long_.kill()
            _ended(long_)
    short = _shell("play", "sweep")  # 3 s
    try:
        t_end = time.monotonic() + 30
        while short.poll() is None and time.monotonic() < t_end:
            assert table_holder(profile) is None
            time.sleep(0.05)
        err = short.stderr.read() if short.stderr else ""
        assert _ended(short) == 0, err
    finally:
        if short.poll() is None:
            short.kill()
            _ended(short)


def _console_refusal(plugins) -> str:
    """What a console of the profile says of an audition now."""
    from console.session.core import ConsoleSession

    session = ConsoleSession(Context("sim", plugins), fast=True)
    return session.held_why()


def test_a_map_measurement_from_a_shell_holds_the_table(plugins, tmp_path):
    """A roving-sensor measurement plays chirps for minutes and measures what the plate
    does: the console's plays meanwhile would be measured too; refused, naming it."""
    profile = load_profile("sim", plugins)
    out = str(tmp_path / "map.npz")
    args = ("frf", "measure", "--sensor", "accelerometer", "--out", out, "--points", "1")
    proc = _shell(*args, "--repeats", "1")
    try:
        who = _held(profile, proc)
        assert who.startswith("haptable frf measure --sensor accelerometer"), who
        assert f"(pid {proc.pid})" in who, who
        assert "ctrl+c in its shell stops it" in _console_refusal(plugins)
    finally:
        proc.send_signal(signal.SIGINT)
        _ended(proc, 60)
    assert table_holder(profile) is None


def test_the_console_s_demo_holds_the_table_for_a_shell(plugins, tmp_path):
    """The other way round: while the console runs a demo, a shell's demo or study run is
    refused (busy, exit 5) naming it, as the console refuses theirs."""
    from ..tui.test_demos import _start

    profile = load_profile("sim", plugins)

    async def scenario():
        app = HapTableApp(Context("sim", plugins), fast=True, initial="scenes")
        async with app.run_test(size=(80, 24)) as pilot:
            await _start(app, pilot, "knob")
            who = f"the knob demo (the console's, pid {os.getpid()})"
            demo = await asyncio.to_thread(haptable, "demo", "flow", "--seconds", "1")
            assert demo.returncode == 5, demo.stderr
            assert f"busy: {who} holds the outputs" in demo.stderr, demo.stderr
            run = ("study", "run", "exp1", "--participant", "P09", "--simulate")
            study = await asyncio.to_thread(haptable, *run, "--out", str(tmp_path / "s"))
            assert study.returncode == 5 and who in study.stderr, study.stderr
            await asyncio.to_thread(app.session.demos.stop)
            assert not table_hold_file(profile).exists()

    asyncio.run(scenario())
