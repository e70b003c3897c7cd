"""Sound-card output through PortAudio (the ``sounddevice`` package).

Float32 channels as ``[audio] channels`` names them (by default two: left piezo
amplifier, right screen amplifier; e.g. five for a patch each and the screen). The PortAudio
callback pulls every block from the source (the safety gate) and never raises: an
exception or a bad sample from the source silences the output for the rest of the
stream (state ``fault``). A device that disappears ends the stream (state ``lost``).
In both cases a source with ``estop(reason, wait=False)`` (the gate) is told.

``stop()`` never cuts the gate's ramp down: the callbacks keep pulling until the last
block with sound in it has reached the DAC (the ramp, then the gate's silence), then the
stream is stopped so that what is queued plays out (``stream.stop()``), bounded by
``close_timeout_s``; ``abort()`` (which drops the queue) is only the fallback. Waiting
for the silence first matters: PortAudio's ALSA host API drops the ALSA buffer even on a
stop (its drain is disabled), and JACK's silences the next period.

PortAudio's ``output_underflow`` flag is counted per cause: ``slow_fill`` when the
callback before it spent longer than a block period in the source's ``fill``, else
``late_callback`` (the callback thread came late: the machine, not the gate).
``sounddevice`` is imported only when a stream is opened or probed, so machines without
PortAudio can still run the twin.

Duplex: when the profile names inputs (``[audio_inputs.NAME]``) one ``sd.Stream`` opens
the device's inputs beside its outputs; the callback fills the outputs from the gate as
always, then copies the input block into an ``InputRing`` at the clock of the output block
it filled (``read_inputs(a, b)``, ``input_clock()``): recording never plays anything.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from console.plugin_api import (
    BlockSource,
    ChannelLayout,
    DeviceStatus,
    InputSpec,
    OutputDevice,
    device_buffer_latency_s,
    input_specs,
    summarize_s,
)
from plugins.drivers.errors import DeviceError
from plugins.drivers.input_ring import InputRing

PORTAUDIO_FIX = "install PortAudio: apt-get install libportaudio2"
TIMING_WINDOW = 2000  # callbacks kept for the period / fill-time statistics
UNDERFLOW_CAUSES = ("late_callback", "slow_fill")
#: ``stop()`` gives up on callbacks that stopped coming after this many block periods
STALLED_PERIODS = 4

_open_streams = 0  # streams this process holds open; PortAudio is only rescanned when 0
_open_lock = threading.Lock()


def load_sounddevice() -> Any:
    """Import ``sounddevice``; a missing PortAudio becomes a DeviceError with the fix."""
    try:
        import sounddevice
    except OSError as exc:  # sounddevice raises OSError when libportaudio is absent
        raise DeviceError(f"sounddevice: PortAudio not found ({exc}); {PORTAUDIO_FIX}") from None
    return sounddevice


def _label(dev: dict, hostapis: Sequence[dict]) -> str:
    api = hostapis[dev["hostapi"]]["name"] if dev["hostapi"] < len(hostapis) else "?"
    return f"{dev['name']} ({api})"


def output_devices(
    devices: Sequence[dict], hostapis: Sequence[dict], channels: int = 2
) -> list[tuple[int, str]]:
    """``(index, "name (host API)")`` of every device with at least ``channels`` outputs."""
    return [
        (i, _label(d, hostapis))
        for i, d in enumerate(devices)
        if int(d.get("max_output_channels", 0)) >= channels
    ]


def _kind(channels: int) -> str:
    return "stereo output" if channels == 2 else f"output with {channels} channels"


def find_output_device(
    devices: Sequence[dict],
    hostapis: Sequence[dict],
    name: str,
    default_index: int = -1,
    channels: int = 2,
) -> int:
    """Index of the output with at least ``channels`` channels whose name matches ``name``.

    An exact name (case-insensitive) wins; else a unique substring of "name (host API)".
    An empty name means the system default output. Raises DeviceError listing the
    available outputs when nothing or several things match; a device that matches but
    has too few channels is named with its count.
    """
    outputs = output_devices(devices, hostapis, channels)
    listing = ", ".join(repr(label) for _, label in outputs) or "none"
    if not name:
        if any(i == default_index for i, _ in outputs):
            return default_index
        raise DeviceError(
            f"[audio] device = '': there is no default {_kind(channels)}; "
            f"available outputs: {listing}; set [audio] device to one of them"
        )
    wanted = name.casefold()
    exact = [i for i, _ in outputs if str(devices[i]["name"]).casefold() == wanted]
    if exact:
        return exact[0]
    matches = [(i, label) for i, label in outputs if wanted in label.casefold()]
    if len(matches) == 1:
        return matches[0][0]
    if not matches:
        small = [
            (label, int(devices[i].get("max_output_channels", 0)))
            for i, label in output_devices(devices, hostapis, 1)
            if wanted in label.casefold() or str(devices[i]["name"]).casefold() == wanted
        ]
        if small and channels > 2:
            label, have = small[0]
            raise DeviceError(
                f"[audio] device = {name!r}: {label!r} has {have} output channels, but "
                f"[audio] channels names {channels}; use a {channels}-channel interface "
                f"or fewer channels"
            )
        raise DeviceError(
            f"[audio] device = {name!r}: no {_kind(channels).replace('output', 'output device')} "
            f"matches; "
            f"available outputs: {listing}; plug in the sound card or set "
            f"[audio] device to one of them"
        )
    several = ", ".join(repr(label) for _, label in matches)
    raise DeviceError(
        f"[audio] device = {name!r}: matches several outputs ({several}); "
        f"use a longer part of the name"
    )


def _rescan(sd: Any) -> None:
    """Make PortAudio list devices plugged in (or servers started) since it started."""
    with _open_lock:
        if _open_streams == 0:
            sd._terminate()
            sd._initialize()


def locate(sd: Any, name: str, channels: int = 2) -> tuple[int, str]:
    """``(index, label)`` of the device named ``name`` with at least ``channels`` outputs,
    rescanning once if not found."""

    def attempt() -> tuple[int, str]:
        devices = list(sd.query_devices())
        hostapis = list(sd.query_hostapis())
        default = sd.default.device[1]
        idx = find_output_device(
            devices, hostapis, name, -1 if default is None else int(default), channels
        )
        return idx, _label(devices[idx], hostapis)

    try:
        return attempt()
    except DeviceError:
        _rescan(sd)
        return attempt()


class SounddeviceOutput:
    """A PortAudio output stream fed block by block from the safety gate."""

    def __init__(
        self,
        device: str = "",
        sample_rate_hz: int = 48000,
        block_size: int = 256,
        latency_s: float = 0.0,
        sd: Any = None,
        channels: int = 2,
        inputs: tuple[InputSpec, ...] = (),
    ) -> None:
        self.device = device
        self.channels = int(channels)
        # duplex: the profile's [audio_inputs], kept by the output clock (InputRing)
        self.input_specs = tuple(inputs)
        self._in_cols = tuple(s.channel - 1 for s in self.input_specs)
        self._ring = InputRing(len(inputs), int(sample_rate_hz)) if inputs else None
        self._filled = 0  # samples the gate filled (its clock): the input rows' index
        self.sample_rate_hz = int(sample_rate_hz)
        self.block_size = int(block_size)
        self.latency_s = float(latency_s)
        self._sd = sd
        self.close_timeout_s = 2.0
        self._lock = threading.Lock()
        self._stream: Any = None
        self._source: BlockSource | None = None
        self._silent = True
        self._stopping = False
        self._state = "stopped"
        self._error = ""
        self._label = ""
        self._underruns = 0
        self._underruns_by_cause: dict[str, int] = dict.fromkeys(UNDERFLOW_CAUSES, 0)
        self._last_fill_s = 0.0  # the previous callback's time in the source's fill
        #: when (``clock``) the last block with sound in it has been played by the DAC
        self._sound_until_s = 0.0
        self._handed_sound = False  # the last block handed had sound in it
        self._stream_latency_s = 0.0
        self._last_stop = ""  # how the last stop() ended: drained, aborted or hung
        #: the callbacks' clock (a test may drive it)
        self.clock: Callable[[], float] = time.perf_counter
        self._blocks = 0
        self._callback_errors = 0
        self._t_last_s: float | None = None
        self._periods_s: deque[float] = deque(maxlen=TIMING_WINDOW)  # between callbacks
        self._fills_s: deque[float] = deque(maxlen=TIMING_WINDOW)  # inside source.fill
        self._dac_leads_s: deque[float] = deque(maxlen=TIMING_WINDOW)  # callback -> DAC

    # ------------------------------------------------------------------ lifecycle
    def start(self, source: BlockSource) -> None:
        """Open the device and start pulling blocks from ``source``."""
        if self._stream is not None:
            raise DeviceError(f"audio output {self._label!r} is already started; stop() it first")
        global _open_streams
        sd = self._sd or load_sounddevice()
        index, self._label = locate(sd, self.device, self.channels)
        self._source = source
        self._t_last_s = None
        self._periods_s.clear()
        self._fills_s.clear()
        self._dac_leads_s.clear()
        self._silent = False
        self._stopping = False
        self._error = ""
        self._last_fill_s = 0.0
        self._sound_until_s = 0.0
        self._handed_sound = False
        try:
            kw = dict(
                samplerate=self.sample_rate_hz,
                blocksize=self.block_size,
                dtype="float32",
                latency=self.latency_s if self.latency_s > 0 else "low",
                finished_callback=self._finished,
            )
            if self._ring is None:
                stream = sd.OutputStream(
                    device=index, channels=self.channels, callback=self._callback, **kw
                )
            else:  # one duplex stream: inputs and outputs on the same sample clock
                stream = sd.Stream(
                    device=(index, index),
                    channels=(max(self._in_cols) + 1, self.channels),
                    callback=self._duplex_callback,
                    **kw,
                )
        except Exception as exc:  # PortAudioError, ValueError for bad settings
            self._silent = True
            raise DeviceError(
                f"audio device {self._label!r}: cannot open at {self.sample_rate_hz} Hz, "
                f"block {self.block_size}, {self.channels} channels float32 ({exc}); check "
                f"[audio] sample_rate_hz / block_size match what the device supports"
            ) from None
        with _open_lock:
            _open_streams += 1
        self._stream = stream
        with contextlib.suppress(Exception):  # duplex: (input, output)
            self._stream_latency_s = float(np.atleast_1d(stream.latency)[-1])
        try:
            stream.start()
        except Exception as exc:
            self.stop()
            self._state = "lost"
            self._error = f"cannot start: {exc}"
            raise DeviceError(
                f"audio device {self._label!r}: cannot start the stream ({exc}); "
                f"check it is plugged in and not used by another program"
            ) from None
        self._state = "running"

    def stop(self) -> None:
        """Play out and close the stream. Safe to call twice, from any thread.

        The callbacks keep pulling from the source until the last block with sound in it
        has reached the DAC (the gate's ramp down, then its silence), then
        ``stream.stop()`` plays out what is queued; ``abort()`` only when that fails or
        hangs. Returns within ``close_timeout_s`` even when PortAudio blocks closing a
        stream whose device is gone (it does with a dead JACK server); the stream is then
        abandoned and the state says so.
        """
        global _open_streams
        with self._lock:
            stream, self._stream = self._stream, None
        if stream is None:
            self._silent = True
            return
        self._stopping = True
        deadline = time.monotonic() + self.close_timeout_s
        self._play_out(stream, time.monotonic() + self.close_timeout_s / 3)
        errors: list[str] = []

        def drain() -> None:
            try:
                stream.stop(ignore_errors=True)  # plays out what is queued
            except Exception as exc:  # a vanished device may refuse even this
                errors.append(f"stopping: {exc}")

        drainer = threading.Thread(target=drain, name="sounddevice-drain", daemon=True)
        drainer.start()
        drainer.join(max(0.0, (deadline - time.monotonic()) / 2))
        aborted = drainer.is_alive() or bool(errors)
        self._silent = True

        def close() -> None:
            try:
                if aborted:  # the fallback: drop what is left
                    stream.abort(ignore_errors=True)
                stream.close(ignore_errors=True)
            except Exception as exc:  # a vanished device may refuse even this
                errors.append(f"closing: {exc}")

        closer = threading.Thread(target=close, name="sounddevice-close", daemon=True)
        closer.start()
        closer.join(max(0.0, deadline - time.monotonic()))
        if closer.is_alive():  # leave _open_streams counted: never rescan under it
            hung = "closing the stream hung; restart haptable before using this device again"
            self._last_stop = "hung"
            self._lose(f"audio device {self._label!r} is gone")
            self._error = f"{self._error}; {hung}"
            return
        self._last_stop = "aborted" if aborted else "drained"
        with _open_lock:
            _open_streams -= 1
        if errors:
            self._error = self._error or errors[0]
        if self._state in ("running", "fault"):
            self._state = "stopped" if self._state == "running" else "fault"

    def _play_out(self, stream: Any, until: float) -> bool:
        """Let the callbacks keep pulling until the last block with sound in it has been
        played (the gate's ramp down, then its silence, reached the DAC); gives up at
        ``until`` (``time.monotonic()``) or when the callbacks stopped coming. True if
        the sound has played out."""
        period = self.block_size / self.sample_rate_hz
        while True:
            if self._silent or not self._is_active(stream):
                return not self._handed_sound  # nothing more will play
            now = self.clock()
            if not self._handed_sound and now >= self._sound_until_s:
                return True
            last = self._t_last_s
            if last is None or now - last > STALLED_PERIODS * period:
                return False  # no callbacks coming: nothing more will be pulled
            if time.monotonic() >= until:
                return False
            time.sleep(period / 4)

    @staticmethod
    def _is_active(stream: Any) -> bool:
        try:
            return bool(stream.active)
        except Exception:  # PortAudioError from a vanished device
            return False

    # ------------------------------------------------------------------ callbacks
    def _callback(self, outdata: np.ndarray, frames: int, time_info: Any, status: Any) -> None:
        clock = self.clock
        t0_s = clock()
        if self._t_last_s is not None:
            self._periods_s.append(t0_s - self._t_last_s)
        self._t_last_s = t0_s
        dac_s = getattr(time_info, "outputBufferDacTime", 0.0)
        now_s = getattr(time_info, "currentTime", 0.0)
        lead_s = self._stream_latency_s
        if dac_s > 0 and now_s > 0:  # when this block reaches the DAC (0 if unknown)
            lead_s = dac_s - now_s
            self._dac_leads_s.append(lead_s)
        if getattr(status, "output_underflow", False):
            period_s = frames / self.sample_rate_hz
            cause = "slow_fill" if self._last_fill_s > period_s else "late_callback"
            self._underruns += 1
            self._underruns_by_cause[cause] += 1
        self._blocks += 1
        if self._silent or self._source is None:
            outdata.fill(0.0)
            self._last_fill_s = 0.0
            self._handed_sound = False
            return
        try:
            self._source.fill(outdata)
            self._filled += frames
            self._last_fill_s = clock() - t0_s
            self._fills_s.append(self._last_fill_s)
            if not np.all(np.isfinite(outdata)) or float(np.max(np.abs(outdata))) > 1.0:
                raise ValueError("source produced samples outside [-1, 1] or not finite")
            self._handed_sound = bool(outdata.any())
            if self._handed_sound:  # played out once the DAC is past this block
                self._sound_until_s = t0_s + max(lead_s, 0.0) + frames / self.sample_rate_hz
        except Exception as exc:  # never let the audio thread die with signal on the wire
            outdata.fill(0.0)
            self._silent = True
            self._callback_errors += 1
            self._state = "fault"
            self._error = f"source failed in the audio callback: {type(exc).__name__}: {exc}"
            self._alarm(self._error)

    def _duplex_callback(
        self, indata: np.ndarray, outdata: np.ndarray, frames: int, time_info: Any, status: Any
    ) -> None:
        """The output callback, then the inputs kept at the clock of the block it filled."""
        clock = self._filled
        self._callback(outdata, frames, time_info, status)
        if self._ring is not None and self._filled > clock:
            self._ring.write(clock, indata, self._in_cols)

    # duplex inputs (console.core.input_contracts.RecordsInputs)
    def input_clock(self) -> int:
        """Inputs are kept for the clocks before this one."""
        return self._ring.clock if self._ring is not None else 0

    def read_inputs(self, a: int, b: int) -> np.ndarray:
        """The inputs over clocks ``a..b``, (b - a, inputs) float32 card units."""
        if self._ring is None:
            return np.zeros((max(0, b - a), 0), np.float32)
        return self._ring.read(a, b)

    def _alarm(self, reason: str) -> None:
        """Tell the source (the safety gate's ``estop(reason, wait=False)``) if it listens."""
        estop = getattr(self._source, "estop", None)
        if callable(estop):
            with contextlib.suppress(Exception):  # the audio thread must survive a broken gate
                estop(reason, wait=False)

    def _finished(self) -> None:
        self._silent = True
        if not self._stopping:
            self._lose(
                f"audio device {self._label!r} stopped by itself (unplugged or its server "
                f"died); plug it in and restart the outputs"
            )

    def _lose(self, why: str) -> None:
        self._silent = True
        if self._state != "lost":
            self._state = "lost"
            self._error = self._error or why
            self._alarm(self._error)

    # ------------------------------------------------------------------ status
    def status(self) -> dict[str, Any]:
        """State, output latency, underruns (and per cause: ``underruns_by_cause``), how
        the last ``stop()`` ended (``last_stop``: drained, aborted or hung), and
        per-callback timing (p50/p99/max in ms over the last ``TIMING_WINDOW``
        callbacks): the period between callbacks, the time spent in the source's
        ``fill``, and how far ahead of the DAC each block was written (``dac_lead_ms``,
        when the host API reports it)."""
        stream = self._stream
        latency_s = in_latency_s = float("nan")
        if stream is not None:
            try:
                both = np.atleast_1d(stream.latency)  # duplex: (input, output)
                latency_s, in_latency_s = (
                    float(both[-1]),
                    float(both[0]) if both.size > 1 else in_latency_s,
                )
                if self._state == "running" and not stream.active and not self._stopping:
                    self._finished()
            except Exception as exc:  # PortAudioError from a vanished device
                self._lose(f"audio device {self._label!r}: {exc}")
        return {
            "driver": "sounddevice",
            "device": self._label or self.device,
            "channels": self.channels,
            "state": self._state,
            "sample_rate_hz": self.sample_rate_hz,
            "block_size": self.block_size,
            "latency_s": latency_s,
            "input_latency_s": in_latency_s,
            "underruns": self._underruns,
            "underruns_by_cause": dict(self._underruns_by_cause),
            "last_stop": self._last_stop,
            "blocks": self._blocks,
            "callback_errors": self._callback_errors,
            "period_ms": summarize_s(list(self._periods_s)),
            "fill_ms": summarize_s(list(self._fills_s)),
            "dac_lead_ms": summarize_s(list(self._dac_leads_s)),
            "error": self._error,
        }


def list_devices(profile: Any, sd: Any = None) -> list[OutputDevice]:
    """Every PortAudio device with an output (rescanned first while no stream of this
    process is open): the name ``[audio] device`` takes ("name (host API)"), channels,
    default latencies; a device with too few channels says so in ``note``. Raises
    ``DeviceError`` (with the fix) without PortAudio."""
    sd = sd or load_sounddevice()
    _rescan(sd)
    devices = list(sd.query_devices())
    hostapis = list(sd.query_hostapis())
    default = sd.default.device[1]
    need = ChannelLayout.from_profile(profile).n
    found = []
    for i, d in enumerate(devices):
        ch = int(d.get("max_output_channels", 0))
        if ch < 1:
            continue
        api = hostapis[d["hostapi"]]["name"] if d["hostapi"] < len(hostapis) else "?"
        found.append(
            OutputDevice(
                "sounddevice",
                _label(d, hostapis),
                api,
                ch,
                float(d.get("default_low_output_latency", float("nan"))),
                float(d.get("default_high_output_latency", float("nan"))),
                default=default is not None and i == int(default),
                note="" if ch >= need else f"{ch} output channel{'s' * (ch != 1)}: needs {need}",
            )
        )
    return found


def from_profile(profile: Any) -> SounddeviceOutput:
    """Factory registered as audio output ``sounddevice``."""
    return SounddeviceOutput(
        device=profile.get("audio.device"),
        sample_rate_hz=profile.get("audio.sample_rate_hz"),
        block_size=profile.get("audio.block_size"),
        latency_s=device_buffer_latency_s(profile, profile.get("sounddevice.latency_s")),
        channels=ChannelLayout.from_profile(profile).n,
        inputs=input_specs(profile),
    )


def probe(profile: Any, sd: Any = None) -> DeviceStatus:
    """Is PortAudio there and does the profile's device exist? (does not open it)"""
    name = profile.get("audio.device")
    try:
        sd = sd or load_sounddevice()
    except DeviceError as exc:
        return DeviceStatus("audio_output", "sounddevice", "missing", str(exc), PORTAUDIO_FIX)
    channels = ChannelLayout.from_profile(profile).n
    try:
        _, label = locate(sd, name, channels)
    except DeviceError as exc:
        return DeviceStatus(
            "audio_output",
            "sounddevice",
            "missing",
            str(exc),
            "plug in the sound card, or set [audio] device to one of the listed outputs",
        )
    return DeviceStatus(
        "audio_output", "sounddevice", "ok", f"output {label!r} ({channels} channels)"
    )
