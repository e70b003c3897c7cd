"""The safety kernel: one outputs process per table, a latched e-stop only an operator
resets, an e-stop before any output opened remembered, clients that go away ramped down,
a dead kernel found by the next one, bad messages dropping only their sender, and a
shell e-stop on the standard library alone (issue 24)."""

from __future__ import annotations

import json
import os
import pty
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from console.core.errors import EStopLatched, SafetyRefusal, UserError
from console.core.types import OutputPlan, Segment
from console.kernel.client import open_outputs
from console.kernel.line_server import request
from console.kernel.tables import read_latch, table_for
from console.signals.waveforms import tone

ROOT = Path(__file__).resolve().parents[2]
FS = 48000


def _env(**extra: str) -> dict[str, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT), **extra}
    env.pop("HAPTABLE_TWIN_LOG", None)
    env.update(extra)
    return env


def haptable(*args: str, timeout: float = 60, **env: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "console.cli.entry", *args],
        env=_env(**env),
        capture_output=True,
        text=True,
        timeout=timeout,
    )


def at_terminal(*args: str, timeout: float = 30) -> tuple[int, str]:
    """Run ``haptable ARGS`` in the foreground of a terminal of its own (a pty), as an
    operator types it; (exit status, what it printed)."""
    pid, fd = pty.fork()
    if pid == 0:  # the child: session leader with the pty as its controlling terminal
        os.environ.update(_env())
        os.execv(sys.executable, [sys.executable, "-m", "console.cli.entry", *args])
    out = b""
    t_end = time.monotonic() + timeout
    while time.monotonic() < t_end:
        try:
            chunk = os.read(fd, 4096)
        except OSError:
            break
        if not chunk:
            break
        out += chunk
    _, status = os.waitpid(pid, 0)
    os.close(fd)
    return os.waitstatus_to_exitcode(status), out.decode(errors="replace")


def plan_of(seconds: float, volts: float = 20.0, name: str = "tone") -> OutputPlan:
    x = tone(250, volts, seconds, FS, 0.01)
    return OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),), name=name)


@pytest.fixture
def shared(profile, plugins):
    """The sim table's own (shared) kernel, fast-forward: what every process of the
    profile reaches, `haptable estop` included."""
    out = open_outputs(profile, plugins, fast=True, private=False)
    yield out
    out.close()


# ---------------------------------------------------------------------- the latch
def test_an_estop_latches_and_a_program_cannot_reset_it(shared, profile, plugins):
    shared.play(plan_of(0.05))
    got = haptable("estop")
    assert got.returncode == 0, got.stdout + got.stderr
    assert "confirmed silent" in got.stdout and "latched" in got.stdout
    t_end = time.monotonic() + 5
    while not shared.estopped and time.monotonic() < t_end:
        time.sleep(0.01)
    assert shared.estopped
    with pytest.raises(SafetyRefusal, match="e-stop active"):
        shared.play(plan_of(0.05))
    with pytest.raises(SafetyRefusal, match="only an operator resets"):
        shared.reset("a program")  # the client API: refused in one line
    table = table_for(profile.path)
    line, _ = request(table.control_sock, "reset a script", timeout_s=5)
    assert line.startswith("refused: only an operator resets"), line  # the wire: the same
    assert shared.estopped and read_latch(table) is not None
    got = haptable("reset")  # a program running the command, no terminal
    assert got.returncode == 1 and "refused" in got.stdout
    assert read_latch(table) is not None
    with pytest.raises(EStopLatched, match="haptable reset"):
        open_outputs(profile, plugins, fast=True, private=False)  # a command starting now


def test_an_operator_resets_at_a_terminal_saying_who_and_when(shared, profile):
    haptable("estop")
    code, text = at_terminal("reset")
    assert code == 0, text
    assert "e-stop reset by haptable reset" in text and " on /dev/pts/" in text
    assert "was: haptable estop" in text
    t_end = time.monotonic() + 5
    while shared.estopped and time.monotonic() < t_end:
        time.sleep(0.01)
    assert not shared.estopped and read_latch(table_for(profile.path)) is None
    shared.play(plan_of(0.05))


def test_the_console_lock_holder_may_reset(shared, profile):
    from console.runtime.control import ControlServer

    server = ControlServer(profile, lambda line: "ok")  # this process is the table's console
    try:
        shared.estop("operator")
        assert "e-stop reset by the console" in shared.reset("the console (ctrl+r)")
        shared.play(plan_of(0.05))
    finally:
        server.close()


def test_an_estop_before_any_output_opened_is_remembered(profile, tmp_path):
    got = haptable("estop")
    assert got.returncode == 0 and "no outputs open" in got.stdout, got.stdout
    log = tmp_path / "twin.json"
    play = haptable("play", "sweep", HAPTABLE_TWIN_LOG=str(log))
    assert play.returncode == 4, play.stderr
    err = play.stderr.strip().splitlines()
    assert len(err) == 1 and "e-stop latched" in err[0] and "haptable reset" in err[0]
    assert not log.exists()


def test_an_estop_while_a_command_still_starts_stops_it(tmp_path):
    """`haptable play sweep & sleep 0.3; haptable estop`: the sweep never plays on."""
    log = tmp_path / "twin.json"
    play = subprocess.Popen(
        [sys.executable, "-m", "console.cli.entry", "play", "sweep"],
        env=_env(HAPTABLE_TWIN_LOG=str(log)),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(0.3)
    got = haptable("estop")
    assert got.returncode == 0, got.stdout
    _, err = play.communicate(timeout=60)
    assert play.returncode == 4, err
    if log.exists():  # it had started: nothing after the e-stop
        data = json.loads(log.read_text())
        stops = [e["clock"] for e in data["gate_events"] if e["kind"] == "estop"]
        rec = np.load(log.with_suffix(".npz"))["recording_v"]
        assert stops and not np.any(rec[stops[0] + 64 + 2000 :])


def test_a_private_table_is_not_an_operators_table(profile, plugins):
    """A bench's own twin (its faults and resets) is never reached by a bare `haptable
    estop`, and its owner may reset its own e-stops there."""
    own = open_outputs(profile, plugins, fast=True)  # private
    try:
        got = haptable("estop", "--json")
        tables = json.loads(got.stdout)["tables"]
        assert all(own.table.key not in json.dumps(t) for t in tables)
        assert not own.estopped
        own.estop("the bench's own fault")
        own.reset("the bench")  # its owner: allowed on its private twin
        own.play(plan_of(0.05))
    finally:
        own.close()


# ---------------------------------------------------------------------- the shell path
def test_the_shell_estop_loads_the_standard_library_only():
    code = (
        "import io, contextlib, sys\n"
        "from console.cli.entry import main\n"
        "with contextlib.redirect_stdout(io.StringIO()): main(['estop'])\n"
        "print(' '.join(sorted(sys.modules)))\n"
    )
    got = subprocess.run(
        [sys.executable, "-c", code], env=_env(), capture_output=True, text=True, timeout=30
    )
    mods = set(got.stdout.split())
    assert "console.kernel.shell" in mods, got.stderr
    heavy = {
        m
        for m in mods
        if m.split(".")[0] in ("numpy", "scipy", "textual", "plugins", "pluggy", "sklearn", "cv2")
    }
    assert not heavy, sorted(heavy)
    # the CLI package holds the entry point only; nothing of the layers above the kernel
    above = ("runtime", "session", "tui", "safety", "config", "signals", "benchmarks")
    assert not {
        m
        for m in mods
        if m.startswith("console.")
        and (
            m.split(".")[1] in above or (m.startswith("console.cli.") and m != "console.cli.entry")
        )
    }


# ---------------------------------------------------------------------- clients that go
def test_a_client_killed_mid_plan_is_ramped_down_not_latched(profile, plugins):
    """kill -9 of a process playing a loud tone: the kernel ramps its plan down within
    the slew limit, opens the relays and plays on for the others; nothing latched."""
    from console.safety import Limits

    watcher = open_outputs(profile, plugins, fast=False)  # paced, the shared table
    child = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import time\n"
            "from console.config.plugins import load_plugins\n"
            "from console.config.profile import load_profile\n"
            "from console.kernel.client import open_outputs\n"
            "from console.signals.waveforms import tone\n"
            "from console.core.types import OutputPlan, Segment\n"
            "pm = load_plugins(); p = load_profile('sim', pm)\n"
            "out = open_outputs(p, pm, fast=False)\n"
            "x = tone(250, 60, 3.0, 48000, 0.01)\n"
            "r = out.play(OutputPlan(48000, (Segment(x, 0 * x, frozenset({'PA'})),)), wait=False)\n"
            "while r.t_first_sample_s is None: time.sleep(0.001)\n"
            "print('playing', flush=True); time.sleep(60)\n",
        ],
        env=_env(),
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert child.stdout.readline().strip() == "playing"
        time.sleep(0.2)
    finally:
        child.kill()
        child.wait()
    try:
        t_end = time.monotonic() + 5
        while watcher.status()["busy"] and time.monotonic() < t_end:
            time.sleep(0.01)
        assert not watcher.status()["busy"] and not watcher.estopped
        rec = watcher.recording(as_played=True)[:, 0]  # a late block's hold/ramp included
        loud = np.flatnonzero(rec)
        assert loud.size and np.abs(rec).max() > 55, "it played"
        assert loud[-1] - loud[0] < 1.5 * FS, "it stopped when its process died"
        lim = Limits.from_profile(profile)
        step = lim.column_steps_v(frozenset({"PA"}))[0]
        assert np.abs(np.diff(rec)).max() <= step * 1.0005, "ramped, never cut"
        assert watcher.status()["gate"]["relays_closed"] == []
        watcher.play(plan_of(0.05))  # the table plays on for the others
    finally:
        watcher.close()


def test_a_killed_kernel_is_found_and_latched_by_the_next(profile, plugins):
    out = open_outputs(profile, plugins, fast=True, private=False)
    pid = out.kernel_pid
    os.kill(pid, signal.SIGKILL)
    t_end = time.monotonic() + 5
    while not out.lost and time.monotonic() < t_end:
        time.sleep(0.01)
    assert out.lost and out.estopped
    out.close()
    with pytest.raises(EStopLatched, match=f"pid {pid}.*ended without closing"):
        open_outputs(profile, plugins, fast=True, private=False)


def test_a_malformed_message_drops_only_its_sender(shared, profile):
    table = table_for(profile.path)
    for junk in (
        b"\x00\x00\x00\x05\x00\x00\x00\x00{nope",  # not JSON
        struct.pack("!II", 2**31, 0),  # a header over the bound
        struct.pack("!II", 20, 2**31) + b'{"op":"plan","id":1}',  # a payload over it
        struct.pack("!II", 58, 8)
        + b'{"op":"plan","id":1,"arrays":[["|O",[1]]],"segments":[]}'
        + b"x" * 8,
    ):
        s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        s.settimeout(5)
        s.connect(str(table.kernel_sock))
        s.sendall(junk)
        with pytest.raises((ConnectionResetError, BrokenPipeError, OSError)):
            while s.recv(4096):
                pass
            raise ConnectionResetError
        s.close()
    shared.play(plan_of(0.05))  # the kernel serves on
    assert not shared.estopped


def test_another_profile_on_a_used_table_is_refused_in_one_line(shared, profile, plugins):
    import dataclasses

    changed = dataclasses.replace(
        profile, data={**profile.data, "limits": {**profile.data["limits"], "piezo_max_v": 100.0}}
    )
    with pytest.raises(
        UserError, match=r"open by .*pid.* other output settings \(limits.piezo_max_v"
    ):
        open_outputs(changed, plugins, fast=True, private=False)
    shared.close()
    other = open_outputs(changed, plugins, fast=True, private=False)  # free now: replaced
    try:
        assert other.limits.piezo_max_v == 100.0
    finally:
        other.close()


def test_a_stream_is_parameters_never_code(outputs):
    with pytest.raises(SafetyRefusal, match="described by its parameters"):
        outputs.stream(object(), name="code")


def test_a_stream_rises_under_the_ramp_to_its_own_declared_peak(profile, plugins):
    """A 10 V stream reaching 10 V in 0.5 ms passed when the start envelope was scaled to
    the full range (250 V): the rule is a plan's, to the stream's own declared peak. The
    kernel's synth always ramps; one broken to jump is caught block by block."""
    from console.kernel.table import TableOutputs
    from console.signals.stream_synth import StreamSpec

    spec = StreamSpec(
        sample_rate_hz=FS,
        patches=frozenset(),
        screen=True,
        carrier_max_v=10.0,
        carrier_min_hz=100.0,
        carrier_max_hz=200.0,
        start_hz=150.0,
        glide_ms=0.0,
        ramp_ms=8.0,
        pulse=None,
    )
    with TableOutputs(profile, plugins, fast=True) as table:
        report, synth = table.scheduler.stream(spec, "jumpy")
        real = synth.next_block

        def jump(n: int):  # 0 -> 10 V in 24 samples (0.5 ms), under 250 V's ramp
            piezo, screen = real(n)
            k = synth.samples_out - n + np.arange(n)
            return piezo, np.where(k < 24, 10.0 * k / 24, 10.0) * np.sign(screen + 1e-12)

        synth.next_block = jump
        synth.post((), 150.0, 10.0)
        report.wait(10)
        assert table.gate.estopped and "no start ramp to its peak of 10.0 V" in (
            table.gate.estop_reason
        )
        rec = table.recording()[:, 1]
        assert np.abs(rec).max() < 1.0, "the jump never reached the screen"


def test_only_the_kernel_builds_an_audio_output_or_a_relay_board():
    """``plugins.build("audio_output" | "relay_board", ...)``, or a function that gets such
    a registration and calls a ``factory``, is in ``console/kernel/table.py`` (and the
    kernel's relay guard) and nowhere else in console/ or plugins/ (a driver's probe may
    look, never open for output)."""
    import ast

    kinds = {"audio_output", "relay_board"}

    def kind_arg(call: ast.Call, method: str) -> bool:
        f = call.func
        return (
            isinstance(f, ast.Attribute)
            and f.attr == method
            and bool(call.args)
            and isinstance(call.args[0], ast.Constant)
            and call.args[0].value in kinds
        )

    found = []
    for root in ("console", "plugins"):
        for path in sorted((ROOT / root).rglob("*.py")):
            tree = ast.parse(path.read_text(encoding="utf-8"))
            where = str(path.relative_to(ROOT))
            for node in ast.walk(tree):
                if isinstance(node, ast.Call) and kind_arg(node, "build"):
                    found.append(f"{where}:{node.lineno}")
                if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    calls = [n for n in ast.walk(node) if isinstance(n, ast.Call)]
                    gets = any(kind_arg(c, "get") for c in calls)
                    makes = any(
                        isinstance(c.func, ast.Attribute) and c.func.attr == "factory"
                        for c in calls
                    )
                    if gets and makes:
                        found.append(f"{where}:{node.lineno} ({node.name})")
    # the kernel's outputs, and its relay guard (opens every relay once the kernel died)
    kernel = ("console/kernel/table.py:", "console/kernel/relay_guard.py:")
    assert found and all(f.startswith(kernel) for f in found), found


def test_a_kernel_that_ended_at_start_is_killed_only_while_it_is_the_servers_child():
    """The fork server reaps a kernel that died; its pid may be another process's by the
    time the client gives up on it (pids wrap on a busy machine): the client kills it
    only while the server is still its parent."""
    from console.kernel.spawn import _parent_of

    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        assert _parent_of(child.pid) == os.getpid()
    finally:
        child.kill()
        child.wait()
    assert _parent_of(child.pid) != os.getpid()  # reaped: gone, or another's child


def test_closed_outputs_leave_no_listener_thread_behind(profile, plugins):
    """A console that opens its outputs again and again (each profile change, each
    reconnect) keeps no thread per opening: the listeners hear every e-stop told before
    the close, then their thread ends."""
    tellers, heard = [], []
    for i in range(3):
        out = open_outputs(profile, plugins, fast=True)  # private
        out.add_listener(lambda kind, msg: heard.append((kind, msg)))
        out.estop(f"opening {i}")
        t_end = time.monotonic() + 10
        while (f"opening {i}" not in {m for _, m in heard}) and time.monotonic() < t_end:
            time.sleep(0.01)
        tellers.append(out._teller.thread)  # the thread that told it
        out.close()
    assert [m for k, m in heard if k == "estop"] == [f"opening {i}" for i in range(3)], heard
    for t in tellers:
        assert t is not None
        t.join(timeout=5)
        assert not t.is_alive(), "a closed outputs' listeners' thread still runs"
