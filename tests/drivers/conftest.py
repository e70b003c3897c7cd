"""Fixtures for the real drivers: a JACK dummy server PortAudio can play into, a stub profile.

``jack_server`` starts ``jackd --no-realtime -d dummy -r 48000 -p 256`` under a unique
server name for the test session (PortAudio then lists a correctly paced output device
``system``), and tears it down. ``jack_server.capture()`` loops every PortAudio output
port back into an input stream so a test sees exactly the samples that reached JACK.
Tests using it are ``@pytest.mark.hardware`` and skip with the reason when jackd,
the JACK tools or PortAudio are missing.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pytest

JACK_RATE_HZ = 48000
JACK_PERIOD = 256


class StubProfile:
    """The part of ``console.config.profile.Profile`` the drivers read: ``get("section.key")``."""

    DEFAULTS: dict[str, Any] = {
        "audio.sample_rate_hz": 48000,
        "audio.block_size": 256,
        "audio.device": "",
        "sounddevice.latency_s": 0.0,
        "relays.channels": 8,
        "relays.url": "usb",
        "relays.serial": "",
        "camera.device": "0",
        "camera.width_px": 640,
        "camera.height_px": 480,
        "camera.fps": 60.0,
        "camera.exposure": -1.0,
        "camera.gain": -1.0,
    }

    def __init__(self, **overrides: Any) -> None:
        self.values = dict(self.DEFAULTS)
        self.values.update({k.replace("__", "."): v for k, v in overrides.items()})

    def get(self, key: str) -> Any:
        return self.values[key]


@pytest.fixture
def stub_profile() -> type[StubProfile]:
    """``stub_profile(audio__device="system")`` -> an object with ``get(key)``."""
    return StubProfile


def _jack_tool(tool: str) -> str:
    path = shutil.which(tool)
    if path is None:
        pytest.skip(f"{tool} not found: apt-get install jackd2")
    return path


@dataclass
class JackCapture:
    """An input stream on the JACK device fed by the PortAudio output ports (a loopback)."""

    server: JackServer
    stream: Any = None
    blocks: list[np.ndarray] = field(default_factory=list)

    def _callback(self, indata: np.ndarray, frames: int, time_info: Any, status: Any) -> None:
        self.blocks.append(indata.copy())

    def attach(self) -> None:
        """Connect every PortAudio output port to this capture (call after the output started)."""
        ports = self.server.ports()
        ins = sorted(p for p in ports if p.startswith("PortAudio") and ":in_" in p)
        outs = sorted(p for p in ports if p.startswith("PortAudio") and ":out_" in p)
        assert len(ins) == 2 and len(outs) == 2, f"unexpected JACK ports: {ports}"
        for src, dst in zip(("system:capture_1", "system:capture_2"), ins, strict=True):
            self.server.jack("jack_disconnect", src, dst, check=False)
        for src, dst in zip(outs, ins, strict=True):
            self.server.jack("jack_connect", src, dst)

    def samples(self) -> np.ndarray:
        """Everything captured so far, (n, 2) float32."""
        blocks = list(self.blocks)
        return np.concatenate(blocks) if blocks else np.zeros((0, 2), np.float32)

    def close(self) -> None:
        if self.stream is not None:
            self.stream.abort(ignore_errors=True)
            self.stream.close(ignore_errors=True)
            self.stream = None


@dataclass
class JackServer:
    """A running ``jackd`` dummy server and the PortAudio device that reaches it."""

    name: str
    process: subprocess.Popen
    log_path: Path
    device: str = "system"  # the PortAudio output device name to put in a profile
    sample_rate_hz: int = JACK_RATE_HZ
    block_size: int = JACK_PERIOD

    def jack(self, tool: str, *args: str, check: bool = True) -> str:
        """Run a JACK command-line tool against this server; returns its stdout.

        A loaded machine can make a tool's client fail to open or hang (the server is
        busy with another client): the tool is tried three times before it counts as
        failed, and the failure says whether the server is still running."""
        why = ""
        for _ in range(3):
            try:
                done = subprocess.run(
                    [_jack_tool(tool), "-s", self.name, *args],
                    capture_output=True,
                    text=True,
                    timeout=20,
                )
            except subprocess.TimeoutExpired:
                why = "no answer in 20 s"
                continue
            if done.returncode == 0 or not check:
                return done.stdout
            why = done.stderr.strip()
            time.sleep(0.5)
        alive = "running" if self.process.poll() is None else f"exited {self.process.returncode}"
        raise AssertionError(
            f"{tool} {' '.join(args)} failed 3 times: {why}; jackd {alive}; its log:\n"
            f"{self.log()[-2000:]}"
        )

    def ports(self) -> list[str]:
        return [p.strip() for p in self.jack("jack_lsp").splitlines() if p.strip()]

    def capture(self) -> JackCapture:
        """Open an input stream for a loopback of the PortAudio outputs (see ``attach``)."""
        import sounddevice as sd

        cap = JackCapture(self)
        cap.stream = sd.InputStream(
            device=self.device,
            samplerate=self.sample_rate_hz,
            blocksize=self.block_size,
            channels=2,
            dtype="float32",
            callback=cap._callback,
        )
        cap.stream.start()
        return cap

    def log(self) -> str:
        return self.log_path.read_text(errors="replace")


def _portaudio() -> Any:
    try:
        import sounddevice as sd
    except OSError as exc:
        pytest.skip(f"PortAudio missing ({exc}): apt-get install libportaudio2")
    return sd


def _jack_output_present(sd: Any) -> bool:
    """Rescan PortAudio; True once its JACK host API lists a stereo output."""
    sd._terminate()
    sd._initialize()
    apis = sd.query_hostapis()
    return any(
        "JACK" in apis[d["hostapi"]]["name"] and d["max_output_channels"] >= 2
        for d in sd.query_devices()
    )


def _server_up(name: str) -> bool:
    """The server answers with its ports (a ``jack_lsp`` past its timeout: not yet)."""
    try:
        done = subprocess.run(
            [_jack_tool("jack_lsp"), "-s", name], capture_output=True, text=True, timeout=10
        )
    except subprocess.TimeoutExpired:  # a loaded machine: asked again until the deadline
        return False
    return done.returncode == 0 and "system:playback_1" in done.stdout


def server_name(kind: str) -> str:
    """A test server's name: one per kind and test worker, never a pid. JACK's registry
    of servers (``/dev/shm/jack-shm-registry``) has 8 slots; a server killed (the
    vanishing-device test kills one on purpose) leaves its slot taken until a server of
    the same name starts again, so names made from pids filled it ("Too many servers
    already active") run after run on the same machine."""
    return f"haptable-{kind}-{os.environ.get('PYTEST_XDIST_WORKER', 'main')}"


def start_jackd(name: str, log_path: Path) -> JackServer:
    """Start ``jackd -n NAME --no-realtime -d dummy`` and wait until it answers."""
    jackd = shutil.which("jackd")
    if jackd is None:
        pytest.skip("jackd not found: apt-get install jackd2")
    _jack_tool("jack_lsp")
    with open(log_path, "wb") as log:
        proc = subprocess.Popen(
            # -t: a client may take 10 s to answer before the server drops it (a loaded
            # machine runs the test's PortAudio client late, not wrong)
            [jackd, "-n", name, "--no-realtime", "-t", "10000", "-d", "dummy"]
            + ["-r", str(JACK_RATE_HZ), "-p", str(JACK_PERIOD)],
            stdout=log,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            start_new_session=True,
        )
    server = JackServer(name, proc, log_path)
    try:
        deadline = time.monotonic() + 15.0
        while not _server_up(name):
            if proc.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"jackd did not come up; its log:\n{server.log()}")
            time.sleep(0.2)
    except BaseException:  # no fixture holds it yet: stopped here, never left running
        stop_jackd(server)
        raise
    return server


def stop_jackd(server: JackServer) -> None:
    proc = server.process
    if proc.poll() is None:
        proc.terminate()
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(timeout=5)


@pytest.fixture
def jackd_factory(tmp_path: Path) -> Iterator[Any]:
    """``jackd_factory(name) -> JackServer``: a private server for one test (stopped after)."""
    started: list[JackServer] = []

    def start(name: str) -> JackServer:
        server = start_jackd(name, tmp_path / f"{name}.log")
        started.append(server)
        return server

    yield start
    for server in started:
        stop_jackd(server)


@pytest.fixture(scope="session")
def jack_server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[JackServer]:
    """A ``jackd`` dummy server at 48 kHz / 256 frames for the session (see module doc)."""
    sd = _portaudio()
    name = server_name("test")
    server = start_jackd(name, tmp_path_factory.mktemp("jack") / "jackd.log")
    saved = {k: os.environ.get(k) for k in ("JACK_DEFAULT_SERVER", "JACK_NO_START_SERVER")}
    os.environ["JACK_DEFAULT_SERVER"] = name  # PortAudio's libjack client reads these
    os.environ["JACK_NO_START_SERVER"] = "1"
    try:
        if not _jack_output_present(sd):
            pytest.skip(
                "jackd runs but this PortAudio has no JACK host API: use Debian's libportaudio2"
            )
        yield server
    finally:
        # the server ends after this process does (``_stop_after_us``): closing
        # PortAudio's JACK client at the session's end, in a worker full of other tests'
        # threads, killed the worker there ("node down: Not properly terminated", its
        # jackd left running); nothing in this process uses PortAudio after the session
        _stop_after_us(server)
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


#: the watcher of ``_stop_after_us``: this process gone (or a zombie), jackd is asked to
#: stop, and killed if it has not within 15 s (a client it waits for, ``-t 10000``)
_WATCH = (
    "while kill -0 $0 2>/dev/null && ! grep -qs '^State:[[:space:]]*Z' /proc/$0/status; "
    "do sleep 0.5; done; kill $1 2>/dev/null; "
    "n=0; while kill -0 $1 2>/dev/null && [ $n -lt 30 ]; do sleep 0.5; n=$((n+1)); done; "
    "kill -9 $1 2>/dev/null"
)


def _stop_after_us(server: JackServer) -> None:
    """Stop ``server`` once this process has exited (a watcher in a session of its own)."""
    subprocess.Popen(
        ["sh", "-c", _WATCH, str(os.getpid()), str(server.process.pid)],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )  # fmt: skip


def wait_until(predicate: Any, timeout_s: float = 10.0, what: str = "condition") -> None:
    """Poll ``predicate`` (not a timing assertion: a generous bound on a wait)."""
    deadline = time.monotonic() + timeout_s
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")
        time.sleep(0.01)


@pytest.fixture
def wait() -> Any:
    """``wait(predicate, timeout_s, what)``: poll until true, fail after the timeout."""
    return wait_until
