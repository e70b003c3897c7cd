"""The sounddevice driver through real PortAudio into a JACK dummy server (paced like a card)."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from plugins.drivers.audio_sounddevice import SounddeviceOutput, from_profile

#: one JACK dummy server (a session fixture) serves them all: on one xdist worker
pytestmark = [pytest.mark.hardware, pytest.mark.xdist_group("jack")]


class KnownSource:
    """Zeros until armed, then ``n_blocks`` of a known random sequence, then zeros.

    Records every block it emitted and the monotonic time of each ``fill`` call.
    """

    def __init__(self, n_blocks: int, block_size: int, seed: int = 7) -> None:
        rng = np.random.default_rng(seed)
        self.sequence = rng.uniform(-0.9, 0.9, (n_blocks * block_size, 2)).astype(np.float32)
        self.armed = threading.Event()
        self.emitted: list[np.ndarray] = []
        self.known_times_s: list[float] = []
        self.pos = 0
        self.zero_blocks_after = 0

    @property
    def idle(self) -> bool:
        return not self.armed.is_set() or self.pos >= len(self.sequence)

    def fill(self, out: np.ndarray) -> None:
        n = len(out)
        if self.armed.is_set() and self.pos < len(self.sequence):
            out[:] = self.sequence[self.pos : self.pos + n]
            self.pos += n
            self.known_times_s.append(time.monotonic())
        else:
            out.fill(0.0)
            if self.pos >= len(self.sequence):
                self.zero_blocks_after += 1
        self.emitted.append(out.copy())

    @property
    def done(self) -> bool:
        return self.pos >= len(self.sequence) and self.zero_blocks_after >= 8


def test_known_sequence_reaches_jack_paced_and_bit_exact(jack_server, stub_profile, wait):
    n_blocks = 150  # 0.8 s at 48 kHz / 256
    profile = stub_profile(
        audio__device=jack_server.device,
        audio__sample_rate_hz=jack_server.sample_rate_hz,
        audio__block_size=jack_server.block_size,
    )
    out = from_profile(profile)
    source = KnownSource(n_blocks, out.block_size)
    capture = jack_server.capture()
    try:
        out.start(source)
        capture.attach()
        wait(lambda: len(capture.blocks) > 4, 10, "the loopback capture to run")
        source.armed.set()
        wait(lambda: source.done, 20, "the known sequence to play")
        wait(lambda: len(capture.samples()) > 0 and source.done, 5, "capture")
        time.sleep(0.05)
        status = out.status()
    finally:
        out.stop()
        capture.close()

    # the callback was paced by the device clock: ~5.3 ms per block, not 300x faster like
    # the ALSA null device (a loose bound: timing belongs in benchmarks)
    wall_s = source.known_times_s[-1] - source.known_times_s[0]
    nominal_s = (n_blocks - 1) * out.block_size / out.sample_rate_hz
    assert nominal_s / 3 < wall_s < nominal_s * 3, (wall_s, nominal_s)

    # what reached JACK is exactly what the source emitted, sample for sample
    played = capture.samples()
    first = int(np.flatnonzero(np.any(played != 0, axis=1))[0])
    got = played[first : first + len(source.sequence)]
    assert got.shape == source.sequence.shape
    np.testing.assert_array_equal(got, source.sequence)
    assert not np.any(played[first + len(source.sequence) :])  # silence afterwards

    emitted = np.concatenate(source.emitted)
    start = int(np.flatnonzero(np.any(emitted != 0, axis=1))[0])
    np.testing.assert_array_equal(emitted[start : start + len(source.sequence)], source.sequence)

    assert status["state"] == "running"
    assert status["device"].startswith("system")
    assert 0 < status["latency_s"] < 1
    assert status["callback_errors"] == 0
    assert status["blocks"] >= n_blocks
    assert out.status()["state"] == "stopped"
    out.stop()  # twice is fine


def test_source_exception_silences_jack_output(jack_server, wait):
    class Exploding:
        idle = False

        def __init__(self) -> None:
            self.calls = 0

        def fill(self, out: np.ndarray) -> None:
            self.calls += 1
            out.fill(0.5)
            if self.calls == 20:
                raise RuntimeError("effect blew up mid-stimulus")

    out = SounddeviceOutput(jack_server.device, jack_server.sample_rate_hz, jack_server.block_size)
    source = Exploding()
    capture = jack_server.capture()
    try:
        out.start(source)
        capture.attach()
        wait(lambda: out.status()["state"] == "fault", 10, "the fault")
        n_at_fault = len(capture.blocks)
        wait(lambda: len(capture.blocks) > n_at_fault + 20, 10, "more blocks")
        status = out.status()
    finally:
        out.stop()
        capture.close()
    assert source.calls == 20  # never asked again after it raised
    assert "effect blew up" in status["error"]
    played = capture.samples()
    assert np.all(played[-10 * out.block_size :] == 0)  # silent, stream still alive


def test_wrong_device_name_lists_the_jack_device(jack_server):
    from plugins.drivers.errors import DeviceError

    out = SounddeviceOutput("no such card", jack_server.sample_rate_hz, jack_server.block_size)
    with pytest.raises(DeviceError, match=r"'system \(JACK Audio Connection Kit\)'"):
        out.start(KnownSource(1, 256))


VANISH_SCRIPT = r"""
import os, signal, sys, time
from plugins.drivers.audio_sounddevice import SounddeviceOutput

class Source:
    idle = False
    def __init__(self):
        self.alarms = []
    def fill(self, out):
        out.fill(0.1)
    def estop(self, reason, *, wait=True):
        self.alarms.append(wait)

def until(pred, what):
    deadline = time.monotonic() + 15
    while not pred():
        if time.monotonic() > deadline:
            print("TIMEOUT", what, flush=True)
            os._exit(3)
        time.sleep(0.01)

src = Source()
out = SounddeviceOutput("system", 48000, 256)
out.close_timeout_s = 1.0
out.start(src)
until(lambda: out.status()["blocks"] > 20, "blocks")
os.kill(int(os.environ["JACKD_PID"]), signal.SIGTERM)
until(lambda: out.status()["state"] == "lost", "lost")
print("STATE", out.status()["state"], flush=True)
print("ALARMS", src.alarms, flush=True)
out.stop()
print("STOPPED", out.status()["state"], flush=True)
# PortAudio's JACK backend asserts in Pa_Terminate once its server died (pa_jack.c):
os._exit(0)
"""


def test_jack_server_dying_mid_stream_is_lost_and_stop_returns(jackd_factory, tmp_path):
    """The device vanishing under a running stream (here: its JACK server killed)."""
    import os
    import subprocess
    import sys

    _ = pytest.importorskip("sounddevice", exc_type=OSError)
    from .conftest import server_name

    name = server_name("vanish")
    server = jackd_factory(name)
    env = dict(os.environ, JACK_DEFAULT_SERVER=name, JACK_NO_START_SERVER="1")
    env["JACKD_PID"] = str(server.process.pid)
    done = subprocess.run(
        [sys.executable, "-c", VANISH_SCRIPT], env=env, capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    assert "STATE lost" in lines
    assert "ALARMS [False]" in lines  # the gate is told once, without blocking the callback
    assert "STOPPED lost" in lines  # stop() came back although PortAudio hangs closing
