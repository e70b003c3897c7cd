"""The console's command channel (``console.runtime.control``): private, bounded, one
console at a time, and no idle or flooding client can keep an e-stop from it."""

from __future__ import annotations

import os
import socket
import threading
import time

import pytest

from console.core.errors import UserError
from console.kernel.private_dir import runtime_dir
from console.runtime.control import ControlServer, send_command, socket_path

from .conftest import connect


def _server(profile, calls=None):
    calls = [] if calls is None else calls
    return ControlServer(profile, lambda line: calls.append(line) or "ok: silenced")


def test_the_socket_lives_in_the_private_directory_mode_0600(profile):
    srv = _server(profile)
    try:
        path = socket_path(profile)  # in its table's folder, beside the kernel's files
        assert path.parent.parent == runtime_dir() / "tables"
        assert os.stat(path.parent).st_mode & 0o777 == 0o700
        assert os.stat(path).st_mode & 0o777 == 0o600
    finally:
        srv.close()
    assert not path.exists()


def test_an_idle_client_does_not_keep_the_estop_from_the_console(profile):
    calls: list[str] = []
    srv = _server(profile, calls)
    idle = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    idle.settimeout(2.0)
    idle.connect(str(socket_path(profile)))
    try:
        t0 = time.monotonic()
        assert send_command(profile, "estop", timeout_s=1.0) == "ok: silenced"
        assert time.monotonic() - t0 < 0.5
    finally:
        idle.close()
        srv.close()
    assert calls == ["estop"]


def test_fifty_idle_clients_do_not_keep_the_estop_from_the_console(profile):
    srv = _server(profile)
    idle = []
    try:
        for _ in range(50):
            idle.append(connect(socket_path(profile)))
        assert send_command(profile, "estop", timeout_s=1.0) == "ok: silenced"
    finally:
        for s in idle:
            s.close()
        srv.close()


def _rss_kb() -> int:
    with open("/proc/self/status") as f:
        return next(int(ln.split()[1]) for ln in f if ln.startswith("VmRSS:"))


def test_a_300_mb_line_is_dropped_at_the_bound_without_growing_the_console(profile):
    srv = _server(profile)
    chunk = b"x" * 2**16
    sent = 0
    rss0 = _rss_kb()
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(5.0)
            s.connect(str(socket_path(profile)))
            try:
                while sent < 300 * 2**20:
                    sent += s.send(chunk)
            except OSError:
                pass
        grew_mb = (_rss_kb() - rss0) / 1024
        assert send_command(profile, "estop") == "ok: silenced"
    finally:
        srv.close()
    assert sent < 8 * 2**20, f"the console took {sent / 2**20:.0f} MB of one line"
    assert grew_mb < 20, f"the console grew by {grew_mb:.0f} MB"


def test_one_console_at_a_time(profile):
    first = _server(profile)
    try:
        with pytest.raises(UserError, match=rf"another console already runs .*pid {os.getpid()}"):
            _server(profile)
        assert send_command(profile, "ping") == "pong"  # the first one keeps serving
    finally:
        first.close()
    _server(profile).close()  # and after it, a new one starts


def test_the_socket_of_a_dead_console_is_not_another_console(profile):
    path = socket_path(profile)
    dead = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    dead.bind(str(path))  # bound, then the process "died": nobody listens
    dead.close()
    srv = _server(profile)
    try:
        assert send_command(profile, "ping") == "pong"
    finally:
        srv.close()


def test_a_hung_socket_left_behind_is_replaced_not_obeyed(profile):
    """A socket that accepts and never answers, with no console holding the lock."""
    path = socket_path(profile)
    hung = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    hung.bind(str(path))
    hung.listen(4)
    try:
        srv = _server(profile)
        try:
            assert send_command(profile, "ping") == "pong"
        finally:
            srv.close()
    finally:
        hung.close()


def test_a_console_socket_of_another_uid_is_not_believed(profile, monkeypatch):
    from console.kernel import line_server

    srv = _server(profile)
    real = line_server.peer_cred
    monkeypatch.setattr(line_server, "peer_cred", lambda s: (real(s)[0], 12345, 12345))
    try:
        assert send_command(profile, "estop") is None
    finally:
        monkeypatch.undo()
        srv.close()


def test_a_shared_runtime_directory_is_refused(profile):
    d = runtime_dir()
    os.chmod(d, 0o777)
    with pytest.raises(UserError, match="chmod 700"):
        _server(profile)


def test_the_server_keeps_serving_while_a_command_is_slow(profile):
    gate = threading.Event()

    def handler(line: str) -> str:
        if line == "slow":
            gate.wait(5)
        return "ok"

    srv = ControlServer(profile, handler)
    try:
        th = threading.Thread(target=send_command, args=(profile, "slow", 5.0), daemon=True)
        th.start()
        time.sleep(0.1)
        assert send_command(profile, "estop", timeout_s=0.5) == "ok"
        gate.set()
        th.join(5)
    finally:
        srv.close()
