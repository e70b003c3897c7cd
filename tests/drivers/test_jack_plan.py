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
        t_end = time.monotonic() + 15
        while pid_alive(out.kernel_pid) and time.monotonic() < t_end:
            time.sleep(0.02)
    assert not pid_alive(out.kernel_pid), "the table's kernel ended with its last client"
    assert not report.error
    # paced by the device clock (loose bound: timing belongs in benchmarks)
    assert plan.duration_s * 0.8 < wall_s < plan.duration_s * 4, (wall_s, plan.duration_s)
    # what reached JACK equals the plan, segment by segment (card units, float32)
    got = capture.samples()[:, 0]
    scale = out.limits.piezo_card_v
    for seg in plan.segments:
        want = (seg.piezo_v / scale).astype(np.float32)
        k = int(np.argmax(np.abs(want) > 0))
        idx = np.flatnonzero(np.isclose(got, want[k], atol=1e-7))
        assert any(
            np.allclose(got[i - k : i - k + want.size], want, atol=1e-6)
            for i in idx
            if i - k >= 0 and i - k + want.size <= got.size
        ), seg.label
    assert all(r.level_v == (0.0, 0.0) for r in log)
    # underruns are not asserted: the non-realtime dummy server drops callbacks even when
    # the gate is idle on a loaded machine; `haptable bench` reports them.
    assert status["audio"]["driver"] == "sounddevice"
