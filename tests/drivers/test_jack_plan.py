"""A whole OutputPlan through the table's kernel (gate + scheduler + sounddevice, in its
own process) into JACK's dummy server."""

from __future__ import annotations

import time

import numpy as np
import pytest

from console.config.profile import PROJECT_PROFILES, load_profile
from console.kernel.client import open_outputs
from console.kernel.private_dir import pid_alive
from console.signals.stimuli import make_stimulus

#: one JACK dummy server (a session fixture) serves them all: on one xdist worker
pytestmark = [pytest.mark.hardware, pytest.mark.xdist_group("jack")]


def test_plan_plays_paced_and_equal_through_portaudio(jack_server, plugins, tmp_path, wait):
    text = (PROJECT_PROFILES / "sim.toml").read_text()
    text = text.replace(
        '[audio]\ndriver = "twin"',
        f'[audio]\ndriver = "sounddevice"\ndevice = "{jack_server.device}"',
    )
    text = text.replace("block_size = 64", f"block_size = {jack_server.block_size}")
    path = tmp_path / "jack.toml"
    path.write_text(text)
    profile = load_profile(str(path), plugins)
    plan = make_stimulus("relay-walk", jack_server.sample_rate_hz)
    capture = jack_server.capture()
    out = open_outputs(profile, plugins)
    try:
        capture.attach()
        wait(lambda: len(capture.blocks) > 4, 10, "the loopback capture to run")
        t0 = time.monotonic()
        report = out.play(plan)
        wall_s = time.monotonic() - t0
        time.sleep(0.2)
        log = out.relay_log()
        status = out.status()
    finally:
        out.close()
        capture.close()
        # the table's kernel holds the sound card until it ends (its linger after the last
        # client): the next test on this JACK server must find only its own ports
        t_end = time.monotonic() + 60  # its linger, then closing the stream (a loaded CI: >15 s)
        while pid_alive(out.kernel_pid) and time.monotonic() < t_end:
            time.sleep(0.02)
    assert not pid_alive(out.kernel_pid), "the table's kernel ended with its last client"
    assert not report.error
    # paced by the device clock (loose bound: timing belongs in benchmarks)
    assert plan.duration_s * 0.8 < wall_s < plan.duration_s * 4, (wall_s, plan.duration_s)
    # what reached JACK is the plan, sample for sample (card units, float32): every
    # period the loopback caught is a slice of a segment, in order, and every segment
    # came through (a dummy server on a loaded machine drops whole periods: not the
    # table's doing, counted by `haptable bench`, so coverage is bounded, not total)
    scale = out.limits.piezo_card_v
    wants = [(seg.piezo_v / scale).astype(np.float32) for seg in plan.segments]
    found, at = [], (0, 0)
    for b in list(capture.blocks):
        if np.any(b[:, 0]):
            f = _where_in_plan(b[:, 0], wants, at)
            assert f is not None, f"a period that is no slice of the plan after {at}"
            found.append(f)
            at = (f[0], f[1] + 1)
    for i, seg in enumerate(plan.segments):
        got = sum(n for j, _, n in found if j == i)
        assert got >= 0.5 * np.count_nonzero(wants[i]), (seg.label, got)
    assert all(r.level_v == (0.0, 0.0) for r in log)
    # underruns are not asserted: the non-realtime dummy server drops callbacks even when
    # the gate is idle on a loaded machine; `haptable bench` reports them.
    assert status["audio"]["driver"] == "sounddevice"


def _where_in_plan(
    block: np.ndarray, wants: list[np.ndarray], at: tuple[int, int]
) -> tuple[int, int, int] | None:
    """(segment, offset, samples): the first place at or after ``at`` where ``block``'s
    non-zero part is an exact slice of a segment (what follows the segment's end in the
    block is the gap's silence); the segments may repeat one another."""
    j = int(np.argmax(block != 0))
    for i in range(at[0], len(wants)):
        want = wants[i]
        start = at[1] if i == at[0] else 0
        for p in start + np.flatnonzero(np.isclose(want[start:], block[j], atol=1e-7)):
            n = min(block.size - j, want.size - p)
            if np.allclose(block[j : j + n], want[p : p + n], atol=1e-6) and not np.any(
                block[j + n :]
            ):
                return i, int(p), int(np.count_nonzero(block[j : j + n]))
    return None
