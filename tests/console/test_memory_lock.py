"""Real-time settings of paced outputs: the memory lock (taken while they are open,
refused with the fix when the system does not allow it, released when the last outputs
close) and the GIL switch interval the audio thread needs."""

from __future__ import annotations

import os
import sys

import pytest

from console.kernel import memory_lock

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="mlockall: Linux")


def _locked_kb(pid: int | str = "self") -> int:
    with open(f"/proc/{pid}/status", encoding="ascii") as f:
        return int(next(ln for ln in f if ln.startswith("VmLck:")).split()[1])


@pytest.fixture
def unlocked():
    """Start from an unlocked process: PortAudio's JACK host API, scanned by an earlier
    test in this worker (tests/drivers), locks the whole process's memory (libjack)."""
    import ctypes

    if sys.platform.startswith("linux") and _locked_kb() > 0:
        ctypes.CDLL(None, use_errno=True).munlockall()


@linux_only
def test_not_allowed_is_a_notice_with_the_fix_and_nothing_locked(monkeypatch):
    monkeypatch.setattr(memory_lock, "_may_lock", lambda: (False, "memlock limit 8192 kB"))
    locked, note = memory_lock.lock_memory()
    assert not locked
    assert "memlock limit 8192 kB" in note and "memlock unlimited" in note


@linux_only
def test_paced_outputs_lock_memory_until_the_last_closes(plugins, unlocked):
    """The table's core (what a kernel builds, here two in this process): the lock is
    held while any paced one is open."""
    from console.config.profile import load_profile
    from console.kernel.table import TableOutputs

    if not memory_lock._may_lock()[0]:
        pytest.skip("this machine does not allow locking memory (no CAP_IPC_LOCK)")
    prof = load_profile("sim", plugins)
    assert _locked_kb() == 0
    a = TableOutputs(prof, plugins, fast=False)
    b = TableOutputs(prof, plugins, fast=False)
    try:
        assert a.status()["memory_locked"] and _locked_kb() > 0
        a.close()
        assert _locked_kb() > 0  # b still plays in real time
    finally:
        a.close()
        b.close()
    assert _locked_kb() == 0
    fast = TableOutputs(prof, plugins, fast=True)  # fast-forward: nothing to protect
    try:
        assert not fast.status()["memory_locked"] and _locked_kb() == 0
    finally:
        fast.close()


@linux_only
def test_a_paced_tables_kernel_locks_its_memory_and_its_clients_do_not(plugins, unlocked):
    """The outputs play in the kernel's process: that one locks its memory (its status
    says so); a client holds no audio thread and locks nothing."""
    from console.config.profile import load_profile
    from console.kernel.client import open_outputs

    if not memory_lock._may_lock()[0]:
        pytest.skip("this machine does not allow locking memory (no CAP_IPC_LOCK)")
    prof = load_profile("sim", plugins)
    with open_outputs(prof, plugins, fast=False) as out:
        st = out.status()
        assert st["memory_locked"] and out.memory_locked
        assert st["kernel"]["pid"] == out.kernel_pid != os.getpid()
        assert _locked_kb(out.kernel_pid) > 0
        assert _locked_kb() == 0
    with open_outputs(prof, plugins, fast=True) as fast:  # fast-forward: nothing to protect
        assert not fast.status()["memory_locked"]
        assert _locked_kb(fast.kernel_pid) == 0


def test_paced_outputs_shorten_the_gil_switch_interval(plugins):
    """In the process that runs the audio thread (the kernel's: the table's core)."""
    from console.config.profile import load_profile
    from console.kernel.table import TableOutputs

    before = sys.getswitchinterval()
    try:
        sys.setswitchinterval(0.005)  # Python's default
        prof = load_profile("sim", plugins)
        with TableOutputs(prof, plugins, fast=True):
            assert sys.getswitchinterval() == 0.005  # fast-forward: nothing to keep in time
        with TableOutputs(prof, plugins, fast=False):
            want = prof.get("audio.switch_interval_ms") * 1e-3
            assert sys.getswitchinterval() == pytest.approx(want, rel=1e-3)
    finally:
        sys.setswitchinterval(before)
