"""A process's second and later table kernels come from its fork server: the same kernel
as a fresh interpreter's (its own session, /dev/null for stdin, its table's log, the
client's environment and directory at the time), ready without importing again; the
server ends with its client and the kernels outlive it; a server that cannot serve
leaves the kernels to fresh interpreters."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from console.core.types import OutputPlan, Segment
from console.kernel import spawn
from console.kernel.client import open_outputs
from console.signals.waveforms import tone

ROOT = Path(__file__).resolve().parents[2]
FS = 48000


def _stat(pid: int) -> list[str]:
    with open(f"/proc/{pid}/stat") as f:
        return f.read().rsplit(")", 1)[1].split()


def _ppid(pid: int) -> int:
    return int(_stat(pid)[1])


def _environ(pid: int) -> dict[str, str]:
    with open(f"/proc/{pid}/environ", "rb") as f:
        pairs = [p.split(b"=", 1) for p in f.read().split(b"\0") if b"=" in p]
    return {k.decode(): v.decode() for k, v in pairs}


def _gone(pid: int, timeout_s: float = 10.0) -> bool:
    """``pid`` ended and was reaped (no zombie left)."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if not os.path.exists(f"/proc/{pid}"):
            return True
        time.sleep(0.02)
    return False


def _ended(pid: int, timeout_s: float) -> bool:
    """``pid`` ended (reaped, or a zombie of a parent that does not reap: the machine's
    init, once its server is gone)."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        try:
            if _stat(pid)[0] == "Z":
                return True
        except FileNotFoundError:
            return True
        time.sleep(0.02)
    return False


def _plays(out) -> None:
    x = tone(250, 10.0, 0.05, FS, 0.005)
    out.play(OutputPlan(FS, (Segment(x, np.zeros_like(x), frozenset({"PA"})),), name="t"))
    assert np.abs(out.recording()).max() > 5


def test_the_second_kernel_is_forked_as_a_fresh_one_would_start(
    profile, plugins, monkeypatch, tmp_path
):
    starter = spawn._Starter()
    monkeypatch.setattr(spawn, "_STARTER", starter)
    first = open_outputs(profile, plugins, fast=True)
    try:
        assert _ppid(first.kernel_pid) == os.getpid()  # the first: a fresh interpreter
        assert starter._proc is None  # no server for a process that starts one kernel
        monkeypatch.setenv("HAPTABLE_FORK_PROBE", "set after the first kernel")
        monkeypatch.chdir(tmp_path)
        second = open_outputs(profile, plugins, fast=True)
        try:
            pid = second.kernel_pid
            server = starter._proc.pid
            assert _ppid(pid) == server != os.getpid()
            st = _stat(pid)
            assert int(st[3]) == pid, "a session of its own: its terminal's signals pass by"
            assert _environ(pid)["HAPTABLE_FORK_PROBE"] == "set after the first kernel"
            assert os.readlink(f"/proc/{pid}/cwd") == str(tmp_path)
            assert os.readlink(f"/proc/{pid}/fd/0") == os.devnull
            log = os.readlink(f"/proc/{pid}/fd/2")
            assert log == str(second.table.dir / "kernel.log")
            held = {os.readlink(f"/proc/{pid}/fd/{n}") for n in os.listdir(f"/proc/{pid}/fd")}
            assert not any(h.startswith("socket:") and h in _sockets(server) for h in held)
            _plays(second)  # a kernel like any other: it plays through its gate
            assert Path(f"/proc/{pid}/comm").read_text().strip() == "haptable-kernel"
        finally:
            second.close()
        assert _gone(pid), "a kernel that ended is reaped by its server at once"
    finally:
        first.close()


def _sockets(pid: int) -> set[str]:
    """The sockets ``pid`` holds (the server's end of its client's pair)."""
    out = set()
    for n in os.listdir(f"/proc/{pid}/fd"):
        link = os.readlink(f"/proc/{pid}/fd/{n}")
        if link.startswith("socket:"):
            out.add(link)
    return out


CLIENT = """
import os, sys, time
from console.config.plugins import load_plugins
from console.config.profile import load_profile
from console.kernel.client import open_outputs
plugins = load_plugins()
profile = load_profile("sim", plugins)
a = open_outputs(profile, plugins, fast=False, private=False)
b = open_outputs(profile, plugins, fast=True)
from console.kernel import spawn
print(b.kernel_pid, spawn._STARTER._proc.pid, flush=True)
time.sleep(60)
"""


def test_the_server_ends_with_its_client_and_its_kernels_live_on(profile, plugins):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    env.pop("HAPTABLE_TWIN_LOG", None)
    proc = subprocess.Popen(
        [sys.executable, "-c", CLIENT], stdout=subprocess.PIPE, text=True, env=env, cwd=ROOT
    )
    try:
        kernel, server = map(int, proc.stdout.readline().split())
        shared = open_outputs(profile, plugins, fast=False, private=False)
        try:
            os.kill(proc.pid, signal.SIGKILL)  # the client dies without a word
            proc.wait(10)
            assert _gone(server), "the server ended with its client"
            # the shared table's kernel (its first, from an interpreter) serves on; the
            # private one (forked) closes its client's outputs and ends on its own
            _plays(shared)
            assert _ended(kernel, 15)
        finally:
            shared.close()
    finally:
        proc.kill()
        proc.wait()


def test_a_server_that_cannot_start_leaves_the_kernels_to_interpreters(
    profile, plugins, monkeypatch
):
    starter = spawn._Starter()
    monkeypatch.setattr(spawn, "_STARTER", starter)
    monkeypatch.setattr(spawn, "send_request", _broken)
    outs = [open_outputs(profile, plugins, fast=True) for _ in range(3)]
    try:
        for out in outs:
            assert _ppid(out.kernel_pid) == os.getpid()
            _plays(out)
        assert starter._failed and starter._sock is None
    finally:
        for out in outs:
            out.close()


def _broken(sock, message, fds) -> None:
    raise BrokenPipeError("the server went away")
