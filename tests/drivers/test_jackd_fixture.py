"""The JACK fixtures never leave a ``jackd -n haptable-test-...`` running after the tests:
a server whose wait to come up fails (``jack_lsp`` hanging on a loaded machine past its
timeout, a Ctrl-C) is stopped before the failure leaves ``start_jackd``; it was left
running, no fixture holding it to stop it."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest

from . import conftest as jack

pytestmark = pytest.mark.hardware


def _running(name: str) -> list[int]:
    """The pids of this user's processes ``jackd -n NAME ...``."""
    pids = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            argv = (d / "cmdline").read_bytes().split(b"\0")
            if d.stat().st_uid != os.getuid():
                continue
        except OSError:
            continue
        if argv and argv[0].endswith(b"jackd") and name.encode() in argv:
            pids.append(int(d.name))
    return pids


def _gone(name: str, timeout_s: float = 10.0) -> bool:
    t_end = time.monotonic() + timeout_s
    while _running(name):
        if time.monotonic() > t_end:
            return False
        time.sleep(0.1)
    return True


@pytest.mark.skipif(shutil.which("jackd") is None, reason="jackd not found: apt-get install jackd2")
def test_a_jackd_whose_wait_fails_is_stopped(monkeypatch, tmp_path):
    name = jack.server_name("start")

    def hung(server_name: str) -> bool:
        raise subprocess.TimeoutExpired(["jack_lsp", "-s", server_name], 10)

    monkeypatch.setattr(jack, "_server_up", hung)
    try:
        with pytest.raises(subprocess.TimeoutExpired):
            jack.start_jackd(name, tmp_path / "jackd.log")
        assert _gone(name), f"jackd -n {name} left running"
    finally:
        for pid in _running(name):  # the one this test started, if it was left
            os.kill(pid, signal.SIGKILL)


@pytest.mark.skipif(shutil.which("jackd") is None, reason="jackd not found: apt-get install jackd2")
def test_a_jack_lsp_that_times_out_is_asked_again(monkeypatch, tmp_path):
    """One ``jack_lsp`` past its timeout (a loaded machine) is a server not up yet: the
    wait goes on until its deadline, and the server comes up."""
    name = jack.server_name("start")
    real, calls = subprocess.run, []

    def slow_once(args, **kw):
        calls.append(args)
        if len(calls) == 1:
            raise subprocess.TimeoutExpired(args, kw.get("timeout", 10))
        return real(args, **kw)

    monkeypatch.setattr(jack.subprocess, "run", slow_once)
    server = None
    try:
        server = jack.start_jackd(name, tmp_path / "jackd.log")
        assert server.process.poll() is None and len(calls) >= 2
    finally:
        if server is not None:
            jack.stop_jackd(server)
        for pid in _running(name):
            os.kill(pid, signal.SIGKILL)
    assert _gone(name)
