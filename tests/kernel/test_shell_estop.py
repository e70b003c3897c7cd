"""`haptable estop` reaches every table's outputs process (issue #12, items 6-8; #24).

A CLI demo, play or audition started from a shell is e-stopped by `haptable estop` from
another shell: it says so per table (with the processes using it), the command ends with
its own e-stopped line and exit status 4, and the twin's log shows nothing after the
e-stop. A table whose kernel cannot confirm is named and makes the e-stop fail within its
deadline; idle, huge and many clients of its control socket do not delay it; sockets and
directories of another user are refused.
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from console.cli.main import main
from console.core.errors import UserError
from console.kernel.private_dir import runtime_dir
from console.kernel.tables import Table, table_for, tables_root

from .conftest import connect

ROOT = Path(__file__).resolve().parents[2]
#: the exit status of a command stopped by `haptable estop` (README, Commands)
EXIT_ESTOPPED = 4


def _status(sock: Path) -> dict:
    from console.kernel.line_server import request

    return json.loads(request(sock, "status", timeout_s=2.0)[0])


# ---------------------------------------------------------------------- helpers
def _env(**extra: str) -> dict[str, str]:
    env = {**os.environ, "PYTHONPATH": str(ROOT), **extra}
    env.pop("HAPTABLE_TWIN_LOG", None)
    env.update(extra)
    return env


class _Cli:
    """A `haptable ...` run from a shell; its stderr collected line by line."""

    def __init__(self, *args: str, env: dict[str, str]) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "console.cli.entry", *args],
            cwd=ROOT,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.err: list[str] = []
        self._t = threading.Thread(target=self._read, daemon=True)
        self._t.start()

    def _read(self) -> None:
        for line in self.proc.stderr:
            self.err.append(line.rstrip("\n"))

    def wait_for(self, cond, timeout_s: float, what: str) -> None:
        t_end = time.monotonic() + timeout_s
        while time.monotonic() < t_end:
            if cond():
                return
            if self.proc.poll() is not None:
                raise AssertionError(f"{what}: exited {self.proc.returncode}: {self.err[-5:]}")
            time.sleep(0.05)
        raise AssertionError(f"{what} not reached in {timeout_s:g} s: {self.err[-5:]}")

    def finish(self, timeout_s: float) -> int:
        try:
            code = self.proc.wait(timeout_s)
        finally:
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()
        self._t.join(2)
        return code


def _table_of(prof: str) -> Table:
    return table_for(prof)


def _using(table: Table, pid: int) -> bool:
    """The command of ``pid`` is a client of the table's kernel."""
    try:
        return any(f"(pid {pid})" in c for c in _status(table.control_sock)["clients"])
    except (OSError, ValueError):
        return False


def _silent_after_estop(log_json: Path) -> tuple[int, float]:
    """(e-stop clock, peak before it) from a twin log; asserts nothing plays after it."""
    data = json.loads(log_json.read_text())
    stops = [e for e in data["gate_events"] if e["kind"] == "estop"]
    assert stops and stops[0]["message"].startswith("haptable estop (pid "), data["gate_events"]
    clock = stops[0]["clock"]
    rec = np.load(log_json.with_suffix(".npz"))["recording_v"]
    assert rec.shape[0] > clock, "the twin recorded past the e-stop"
    # the driver ramps from the sample playing at the e-stop (a few samples at the slew
    # limit, inside the block queued ahead): silent from the e-stop's clock on
    after = np.flatnonzero(np.any(rec[clock:] != 0.0, axis=1))
    assert after.size == 0, f"{after.size} non-zero samples after the e-stop"
    return clock, float(np.abs(rec[:clock]).max())


def _estop_cli(env: dict[str, str], *extra: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "console.cli.entry", "estop", *extra],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )


# ---------------------------------------------------------------------- (a) from a shell
#: what runs from a shell; whether `haptable estop` runs as its own process too (the
#: stimuli last 2-3 s: a loaded machine may take that long to start an interpreter, so
#: for them the command's code runs in this test's process)
CASES = {
    "demo knob": (["demo", "knob", "--seconds", "0"], True),
    "play sweep": (["play", "sweep"], False),
    "knob --audition": (["knob", "--audition", "HD+VF"], False),
}


def _patient_sim(tmp_path: Path) -> Path:
    """The sim profile with a watchdog that a loaded test machine does not trip."""
    text = (ROOT / "profiles" / "sim.toml").read_text()
    (tmp_path / "prof").mkdir()
    path = tmp_path / "prof" / "sim.toml"
    path.write_text(text + "\n[runtime]\nwatchdog_ms = 5000\n")
    return path


def _playing(table: Table) -> bool:
    """The table's gate is handing out signal right now."""
    return any(_status(table.control_sock)["level_v"])


@pytest.mark.parametrize("case", list(CASES))
def test_haptable_estop_stops_a_cli_command_run_from_a_shell(case, tmp_path, capsys):
    args, own_process = CASES[case]
    log = tmp_path / "twin.json"
    prof = str(_patient_sim(tmp_path))
    cmd = _Cli("--profile", prof, *args, env=_env(HAPTABLE_TWIN_LOG=str(log)))
    table = _table_of(prof)
    try:
        cmd.wait_for(lambda: _using(table, cmd.proc.pid), 60, "the command uses the table")
        cmd.wait_for(lambda: _playing(table), 60, "the command playing")
        if own_process:
            stop = _estop_cli(_env())
            out, stop_code = stop.stdout + stop.stderr, stop.returncode
        else:  # what `haptable estop` runs (console.cli.entry), in this process
            from console.kernel.shell import main as shell_main

            stop_code = shell_main(["estop"])
            cap = capsys.readouterr()
            out = cap.out + cap.err
    finally:
        code = cmd.finish(20)
    lines = [ln for ln in out.splitlines() if f"(pid {cmd.proc.pid})" in ln]
    assert len(lines) == 1, (out, code, cmd.err[-5:])
    assert "confirmed silent (0 V / 0 V), relays open" in lines[0], lines[0]
    assert f"haptable --profile {prof} {args[0]}" in lines[0] and "table sim " in lines[0]
    assert stop_code == 0, out
    assert code == EXIT_ESTOPPED, cmd.err[-5:]
    said = [e for e in cmd.err if e.startswith("haptable: e-stopped by haptable estop (pid ")]
    assert len(said) == 1, cmd.err[-5:]
    assert not any("Traceback" in e or "internal error" in e for e in cmd.err), cmd.err
    _, peak = _silent_after_estop(log)
    assert peak > 0.0, "the command was playing when the e-stop came"
    assert not _using(table, cmd.proc.pid), "it left the table"


# ---------------------------------------------------------------------- (b) unconfirmable
def _fake_kernel(name: str, *, answer: bytes | None = None):
    """A table's control socket that accepts and answers ``answer`` (never, if None)."""
    d = tables_root() / f"{name}-0123456789"
    d.mkdir(mode=0o700)
    path = d / "control.sock"
    srv = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    srv.bind(str(path))
    srv.listen(8)
    held: list[socket.socket] = []

    def serve() -> None:
        while True:
            try:
                c, _ = srv.accept()
            except OSError:
                return
            held.append(c)
            if answer is not None:
                with contextlib.suppress(OSError):  # the client may have left
                    c.recv(256)
                    c.sendall(answer)

    threading.Thread(target=serve, daemon=True).start()
    return path, srv, held


def test_estop_names_a_table_that_does_not_answer_and_fails_within_its_deadline(shared, capsys):
    from console.kernel.shell import main as shell_main  # what `haptable estop` runs

    hung = [_fake_kernel(f"hung{i}") for i in range(3)]
    try:
        t0 = time.monotonic()
        code = shell_main(["estop", "--timeout", "0.5"])
        took = time.monotonic() - t0
    finally:
        for _, srv, held in hung:
            srv.close()
            for c in held:
                c.close()
    out = capsys.readouterr().out
    assert code == 1, out
    for i in range(3):
        line = next(ln for ln in out.splitlines() if f"table hung{i}:" in ln)
        assert "NOT confirmed: no answer within 0.5 s" in line, line
    mine = [ln for ln in out.splitlines() if "confirmed silent" in ln]
    assert len(mine) == 1, out  # the real outputs of this table: confirmed
    assert shared.wait_safe(2) and shared.status()["gate"]["estopped"]
    assert took < 1.5, f"three hung tables took {took:.2f} s: not reached at once"


def test_a_table_whose_kernel_ended_is_named_and_stays_latched(capsys):
    d = tables_root() / "gone-0123456789"
    d.mkdir(mode=0o700)
    s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    s.bind(str(d / "control.sock"))  # nobody listens on it
    s.close()
    assert main(["estop"]) == 0
    out = capsys.readouterr().out
    assert "table gone: no outputs process answers (it ended); latched" in out, out
    assert "no outputs open" in out
    assert (d / "estop.json").exists()


def _cap() -> dict:
    return {"capture_output": True, "text": True, "timeout": 30}


# ---------------------------------------------------------------------- (c) clients


def _idle_clients(path: Path, n: int) -> list[socket.socket]:
    out = []
    for _ in range(n):
        out.append(connect(path))
    return out


def _confirmed_quickly(outputs, limit_s: float = 1.0) -> None:
    from console.kernel.shell import estop

    t0 = time.monotonic()
    reached, _ = estop(None, 2.0)
    took = time.monotonic() - t0
    (r,) = reached
    assert r.pid == outputs.kernel_pid and r.confirmed, r
    assert took < limit_s, f"the e-stop took {took:.2f} s"
    assert outputs.wait_safe(2) and outputs.status()["gate"]["estopped"]


@pytest.fixture
def shared(profile, plugins):
    """The sim table's shared kernel (fast-forward): what `haptable estop` reaches."""
    from console.kernel.client import open_outputs

    out = open_outputs(profile, plugins, fast=True, private=False)
    yield out
    out.close()


def test_an_idle_client_does_not_delay_the_estop(shared):
    idle = _idle_clients(shared.table.control_sock, 1)
    try:
        _confirmed_quickly(shared)
    finally:
        for s in idle:
            s.close()


def test_fifty_idle_clients_do_not_delay_the_estop(shared):
    idle = _idle_clients(shared.table.control_sock, 50)
    try:
        _confirmed_quickly(shared)
    finally:
        for s in idle:
            s.close()


def test_two_hundred_idle_clients_past_the_limit_still_leave_the_estop(shared):
    idle = _idle_clients(shared.table.control_sock, 200)  # the oldest are dropped
    try:
        _confirmed_quickly(shared)
    finally:
        for s in idle:
            s.close()


def _rss_kb() -> int:
    with open("/proc/self/status") as f:
        return next(int(ln.split()[1]) for ln in f if ln.startswith("VmRSS:"))


def flood(path: Path, total: int = 300 * 2**20) -> int:
    """Send up to ``total`` bytes with no newline; the bytes the server took."""
    chunk = b"x" * 2**16
    sent = 0
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.settimeout(5.0)
        s.connect(str(path))
        try:
            while sent < total:
                sent += s.send(chunk)
        except OSError:  # dropped at the bound (or stalled: the kernel buffer is full)
            pass
    return sent


def test_a_300_mb_line_is_cut_at_the_bound(shared):
    sent = flood(shared.table.control_sock)
    assert sent < 8 * 2**20, f"the kernel took {sent / 2**20:.0f} MB of one line"
    _confirmed_quickly(shared)


def test_a_slow_reader_of_the_answer_does_not_hold_the_server(shared):
    """Many clients send ``status`` and never read: the e-stop is still answered."""
    clients = _idle_clients(shared.table.control_sock, 40)
    for s in clients:
        s.sendall(b"status\n")
    try:
        _confirmed_quickly(shared)
    finally:
        for s in clients:
            s.close()


# ---------------------------------------------------------------------- (d) refused
def test_a_socket_of_another_user_is_refused_and_never_reported_confirmed(capsys):
    path, srv, held = _fake_kernel("planted", answer=b'{"confirmed": true, "why": "silent"}\n')
    try:
        os.chown(path, 12345, -1)  # root here: a socket file of another user
        assert main(["estop"]) == 1
        out = capsys.readouterr().out
        assert "NOT confirmed: refused:" in out and "belongs to uid 12345" in out, out
    finally:
        srv.close()


def test_a_server_of_another_uid_is_refused_by_its_peer_credentials(capsys, monkeypatch):
    from console.kernel import line_server

    path, srv, _ = _fake_kernel("replaced", answer=b'{"confirmed": true, "why": "silent"}\n')
    real = line_server.peer_cred
    monkeypatch.setattr(  # what SO_PEERCRED says of a process of uid 12345
        line_server, "peer_cred", lambda s: (real(s)[0], 12345, 12345)
    )
    try:
        assert main(["estop"]) == 1
    finally:
        srv.close()
    out = capsys.readouterr().out
    assert "replaced" in out and "NOT confirmed: refused:" in out and "uid 12345" in out, out


def test_a_line_server_drops_a_client_of_another_uid_unanswered(tmp_path, monkeypatch):
    from console.kernel import line_server
    from console.kernel.line_server import LineServer, request

    real = line_server.peer_cred

    def cred(s):
        pid, uid, gid = real(s)
        if threading.current_thread().name == "haptable-test-server":  # the server's view
            return pid, 12345, gid
        return pid, uid, gid

    monkeypatch.setattr(line_server, "peer_cred", cred)
    tmp_path.chmod(0o700)
    got: list[str] = []
    srv = LineServer(
        tmp_path / "c.sock", lambda line, pid: got.append(line) or "ok", name="haptable-test-server"
    )
    try:
        with pytest.raises(ConnectionResetError, match="closed without an answer"):
            request(tmp_path / "c.sock", "estop", timeout_s=1.0)
    finally:
        srv.close()
    assert got == [], "a stranger's e-stop did nothing"


@pytest.mark.parametrize("how", ["mode 777", "symlink", "another owner"])
def test_a_shared_or_foreign_runtime_directory_is_refused_in_one_line(how, tmp_path, capsys):
    d = Path(os.environ["XDG_RUNTIME_DIR"]) / "haptable"
    if how == "mode 777":
        d.mkdir(mode=0o700)
        os.chmod(d, 0o777)
        fix = "chmod 700"
    elif how == "symlink":
        (tmp_path / "elsewhere").mkdir(mode=0o700)
        d.symlink_to(tmp_path / "elsewhere")
        fix = "not a plain directory"
    else:
        d.mkdir(mode=0o700)
        os.chown(d, 12345, -1)
        fix = "belongs to uid 12345"
    code = main(["estop"])
    cap = capsys.readouterr()
    assert code == 2
    err = cap.err.strip()
    assert err.count("\n") == 0 and err.startswith("haptable: error: ") and fix in err, err
    with pytest.raises(UserError, match=fix):
        runtime_dir()
    assert main(["play", "sine-PA", "--fast"]) == 2  # no table opens outside it
    assert fix in capsys.readouterr().err


def test_a_tables_files_are_private(shared):
    d = shared.table.dir
    assert d.parent == runtime_dir() / "tables"
    assert os.stat(d.parent).st_mode & 0o777 == 0o700 and os.stat(d).st_mode & 0o777 == 0o700
    for name in ("control.sock", "kernel.sock", "kernel.json", "kernel.lock"):
        assert os.stat(d / name).st_mode & 0o777 == 0o600, name


# ---------------------------------------------------------------------- a demo process
def test_haptable_estop_ends_a_demo_process_of_the_console(profile, tmp_path):
    from console.runtime.demo_process import DemoProcess

    run = DemoProcess(profile, "knob", twin_log=tmp_path / "knob.json")  # the shared table
    try:
        run.wait_started(lambda f, text: None)
        assert main(["estop"]) == 0
        t_end = time.monotonic() + 20
        while run.running and time.monotonic() < t_end:
            time.sleep(0.05)
    finally:
        run.stop()
    assert run.estop_reason and run.estop_reason.startswith("haptable estop (pid ")
    gate = run.final["final"]["outputs"]["gate"]
    assert gate["estopped"] and gate["level_v"] == [0.0, 0.0] and gate["relays_closed"] == []
    _silent_after_estop(Path(run.final["twin_log"]))


# ---------------------------------------------------------------------- files (item 8)
def test_the_consoles_demo_log_goes_to_the_private_directory():
    from console.session.demos import twin_log_path

    p = twin_log_path("knob")
    assert p.parent == runtime_dir() and not str(p).startswith("/tmp/haptable-demo")


def test_a_planted_symlink_at_a_twin_log_is_refused_not_followed(outputs, tmp_path):
    from console.runtime.twin_log import write_twin_log

    victim = tmp_path / "victim"
    victim.write_text("keep")
    for name in ("log.json", "log2.npz"):
        (tmp_path / name).symlink_to(victim)
    with pytest.raises(UserError, match="symlink"):
        write_twin_log(tmp_path / "log.json", outputs, [])
    with pytest.raises(UserError, match="symlink"):
        write_twin_log(tmp_path / "log2.json", outputs, [])
    assert victim.read_text() == "keep"


def test_a_cli_twin_log_through_a_symlink_is_one_line_and_the_target_kept(
    tmp_path, capsys, monkeypatch
):
    victim = tmp_path / "victim"
    victim.write_text("keep")
    (tmp_path / "twin.json").symlink_to(victim)
    monkeypatch.setenv("HAPTABLE_TWIN_LOG", str(tmp_path / "twin.json"))
    assert main(["play", "sine-PA", "--fast"]) == 0
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "is a symlink; refusing" in err, err
    assert victim.read_text() == "keep"


def test_the_demo_hosts_copy_beside_the_env_log_never_follows_a_symlink(
    outputs, tmp_path, monkeypatch
):
    from console.runtime.demo_host import Host

    victim = tmp_path / "victim"
    victim.write_text("keep")
    (tmp_path / "env.demo-knob.json").symlink_to(victim)
    monkeypatch.setenv("HAPTABLE_TWIN_LOG", str(tmp_path / "env.json"))
    host = Host({"demo": "knob", "twin_log": str(tmp_path / "mine.json")}, proto=None)
    host.outputs = outputs
    host.write_logs()
    assert (tmp_path / "mine.json").exists()
    assert victim.read_text() == "keep"


@pytest.mark.parametrize(
    "argv", [["--profile", "nosuch", "estop"], ["estop", "--profile", "profiles/sim.tom"]]
)
def test_estop_with_a_mistyped_profile_stops_every_table_then_says_so(shared, capsys, argv):
    """A mistyped profile must not leave a table playing (a new operator's
    `haptable --profile nosuch estop` stopped nothing): every table is e-stopped and
    latched, then the mistake is said; exit 2."""
    from console.kernel.shell import main as shell_main  # what `haptable estop` runs

    code = shell_main(argv)
    captured = capsys.readouterr()
    assert code == 2, captured
    assert "every table was e-stopped instead" in captured.err, captured.err
    assert "not found" in captured.err, captured.err
    assert "confirmed silent" in captured.out, captured.out
    assert shared.wait_safe(2) and shared.status()["gate"]["estopped"]
