"""Real-time settings of paced outputs: the memory lock (taken while they are open,
refused with the fix when the system does not allow it, released when the last outputs
close) and the GIL switch interval the audio thread needs."""

from __future__ import annotations

import sys

import pytest

from console.runtime import memory_lock

linux_only = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="mlockall: Linux")


def _locked_kb() -> int:
    with open("/proc/self/status", encoding="ascii") as f:
        return int(next(ln for ln in f if ln.startswith("VmLck:")).split()[1])


@linux_only
def test_not_allowed_is_a_notice_with_the_fix_and_nothing_locked(monkeypatch):
    monkeypatch.setattr(memory_lock, "_may_lock", lambda: (False, "memlock limit 8192 kB"))
    locked, note = memory_lock.lock_memory()
    assert not locked
    assert "memlock limit 8192 kB" in note and "memlock unlimited" in note


@linux_only
def test_paced_outputs_lock_memory_until_the_last_closes(plugins):
    from console.profile import load_profile
    from console.runtime.outputs import open_outputs

    if not memory_lock._may_lock()[0]:
        pytest.skip("this machine does not allow locking memory (no CAP_IPC_LOCK)")
    prof = load_profile("sim", plugins)
    a = open_outputs(prof, plugins, fast=False)
    b = open_outputs(prof, plugins, fast=False)
    try:
        assert a.status()["memory_locked"] and _locked_kb() > 0
        a.close()
        assert _locked_kb() > 0  # b still plays in real time
    finally:
        a.close()
        b.close()
    assert _locked_kb() == 0
    fast = open_outputs(prof, plugins, fast=True)  # fast-forward: nothing to protect
    try:
        assert not fast.status()["memory_locked"] and _locked_kb() == 0
    finally:
        fast.close()


def test_paced_outputs_shorten_the_gil_switch_interval(plugins):
    from console.profile import load_profile
    from console.runtime.outputs import open_outputs

    before = sys.getswitchinterval()
    try:
        sys.setswitchinterval(0.005)  # Python's default
        prof = load_profile("sim", plugins)
        with open_outputs(prof, plugins, fast=True):
            assert sys.getswitchinterval() == 0.005  # fast-forward: nothing to keep in time
        with open_outputs(prof, plugins, fast=False):
            want = prof.get("audio.switch_interval_ms") * 1e-3
            assert sys.getswitchinterval() == pytest.approx(want, rel=1e-3)
    finally:
        sys.setswitchinterval(before)
