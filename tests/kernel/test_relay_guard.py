"""The relay guard (``console.kernel.relay_guard``): a kernel killed with a relay closed
leaves it closed on a real board; its guard opens every relay and latches the table.
A kernel that closes its outputs itself ends its guard without a latch."""

from __future__ import annotations

import importlib.util
import json
import os
import signal
import time
from pathlib import Path

import pytest

from console.config.plugins import load_plugins
from console.config.profile import PROJECT_PROFILES, load_profile
from console.core.errors import EStopLatched
from console.kernel.client import open_outputs

HERE = Path(__file__).parent


def _plugin():
    spec = importlib.util.spec_from_file_location(
        "file_relays", HERE / "guard_plugins" / "file_relays.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture
def board_table(tmp_path):
    """A profile whose relays are a file, and that file."""
    pm = load_plugins(extra={"file_relays": _plugin()})
    contacts = tmp_path / "contacts.json"
    text = (PROJECT_PROFILES / "sim.toml").read_text()
    text = text.replace('[relays]           # twin of a Yocto-MaxiCoupler: 8 channels, 350 Vpp\n'
                        'driver = "twin"',
                        f'[relays]\ndriver = "file-relays"\nserial = "{contacts}"')  # fmt: skip
    path = tmp_path / "filerelays.toml"
    path.write_text(text)
    return load_profile(path, pm), pm, contacts


def _closed(contacts: Path) -> list[int]:
    return [i + 1 for i, s in enumerate(json.loads(contacts.read_text())) if s]


def _guard_pids(kernel_pid: int) -> list[int]:
    """The relay guards this test's kernel started (by their command line)."""
    found = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                cmd = (d / "cmdline").read_bytes()
            except OSError:
                continue
            if b"console.kernel.relay_guard" in cmd:
                found.append(int(d.name))
    return found


def test_a_killed_kernel_s_relays_are_opened_by_its_guard(board_table):
    profile, pm, contacts = board_table
    out = open_outputs(profile, pm, fast=True, private=False)
    pid = out.kernel_pid
    out.set_relays({1, 3})
    assert _closed(contacts) == [1, 3], "the board closed them"
    os.kill(pid, signal.SIGKILL)
    t_end = time.monotonic() + 15
    while _closed(contacts) and time.monotonic() < t_end:
        time.sleep(0.05)
    assert _closed(contacts) == [], "the guard opened every relay"
    out.close()
    with pytest.raises(EStopLatched, match=f"pid {pid}.*guard opened every relay"):
        open_outputs(profile, pm, fast=True, private=False)


def test_a_kernel_that_closes_ends_its_guard_and_latches_nothing(board_table):
    profile, pm, contacts = board_table
    out = open_outputs(profile, pm, fast=True, private=False)
    pid = out.kernel_pid
    guards = _guard_pids(pid)
    assert guards, "a board outside the kernel's memory is guarded"
    out.set_relays({2})
    out.close()
    t_end = time.monotonic() + 15
    while any(Path(f"/proc/{g}").exists() for g in guards) and time.monotonic() < t_end:
        time.sleep(0.05)
    assert not any(Path(f"/proc/{g}").exists() for g in guards), "the guard ended"
    assert _closed(contacts) == []
    again = open_outputs(profile, pm, fast=True, private=False)  # no latch
    again.close()
