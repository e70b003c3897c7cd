"""The sounddevice driver against a fake ``sounddevice`` module (no PortAudio needed).

The fake's callbacks run when a test pumps them, on a fake clock the driver's timing reads
(``out.clock``): the tests assert what happened, never how long it took."""

from __future__ import annotations

import threading
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from plugins.drivers import audio_sounddevice as asd
from plugins.drivers.audio_sounddevice import SounddeviceOutput, find_output_device
from plugins.drivers.errors import DeviceError

HOSTAPIS = [{"name": "ALSA"}, {"name": "JACK Audio Connection Kit"}]
DEVICES = [
    {"name": "HDA Intel PCH: ALC3246 Analog (hw:0,0)", "hostapi": 0, "max_output_channels": 2},
    {"name": "USB Audio CODEC: Audio (hw:1,0)", "hostapi": 0, "max_output_channels": 2},
    {"name": "USB Audio mic", "hostapi": 0, "max_output_channels": 0},
    {"name": "system", "hostapi": 1, "max_output_channels": 2},
    {"name": "mono out", "hostapi": 0, "max_output_channels": 1},
]


class FakeStream:
    def __init__(self, sd: FakeSd, **kw: Any) -> None:
        self.sd, self.kw = sd, kw
        self.active = False
        self.closed = False
        self.latency = 0.0107
        sd.streams.append(self)

    def start(self) -> None:
        if self.sd.fail_start:
            raise self.sd.PortAudioError("Device unavailable [PaErrorCode -9985]")
        self.active = True

    def stop(self, ignore_errors: bool = True) -> None:
        """Plays out what is queued (no more callbacks), then the stream is inactive."""
        self.sd.calls.append("stop")
        if self.sd.stop_hangs:
            self.sd.release_stop.wait(10)
        if self.active:
            self.active = False
            self.kw["finished_callback"]()

    def abort(self, ignore_errors: bool = True) -> None:
        self.sd.calls.append("abort")
        if self.active:
            self.active = False
            self.kw["finished_callback"]()

    def close(self, ignore_errors: bool = True) -> None:
        self.sd.calls.append("close")
        if self.sd.close_hangs:
            self.sd.release_close.wait(10)
        self.closed = True

    def pump(self, n_blocks: int = 1, underflow: bool = False) -> np.ndarray:
        """Run the callback like PortAudio would; returns what it wrote."""
        frames = self.kw["blocksize"]
        outs = []
        for k in range(n_blocks):
            out = np.full((frames, 2), 7.0, np.float32)  # garbage, must be overwritten
            if self.sd.clock is not None:
                self.sd.clock.t += frames / self.kw["samplerate"]
            now = 50.0 + k * frames / self.kw["samplerate"]
            when = SimpleNamespace(currentTime=now, outputBufferDacTime=now + 0.008)
            status = SimpleNamespace(output_underflow=underflow)
            self.kw["callback"](out, frames, when, status)
            outs.append(out)
        return np.concatenate(outs)

    def vanish(self) -> None:
        """The device is unplugged: PortAudio ends the stream by itself."""
        self.active = False
        self.kw["finished_callback"]()


class FakeSd:
    class PortAudioError(Exception):
        pass

    def __init__(self, devices: list[dict] | None = None) -> None:
        self.devices = list(DEVICES if devices is None else devices)
        self.default = SimpleNamespace(device=[-1, 1])
        self.streams: list[FakeStream] = []
        self.fail_start = False
        self.close_hangs = False
        self.release_close = threading.Event()
        self.stop_hangs = False
        self.release_stop = threading.Event()
        self.calls: list[str] = []  # stop / abort / close, in order
        self.clock: FakeClock | None = None  # advanced a block period per callback
        self.rescans = 0
        self.plugged_on_rescan: list[dict] = []

    def query_devices(self) -> list[dict]:
        return self.devices

    def query_hostapis(self) -> list[dict]:
        return HOSTAPIS

    def _terminate(self) -> None:
        self.rescans += 1

    def _initialize(self) -> None:
        self.devices += self.plugged_on_rescan
        self.plugged_on_rescan = []

    def OutputStream(self, **kw: Any) -> FakeStream:  # noqa: N802 (mirrors sounddevice)
        if kw["samplerate"] not in (44100, 48000):
            raise self.PortAudioError("Invalid sample rate [PaErrorCode -9997]")
        return FakeStream(self, **kw)


class FakeClock:
    def __init__(self) -> None:
        self.t = 100.0

    def now(self) -> float:
        return self.t


class RampSource:
    idle = False

    def __init__(self) -> None:
        self.n = 0
        self.alarms: list[tuple[str, bool]] = []

    def estop(self, reason: str, *, wait: bool = True) -> None:
        """Like the safety gate's: the driver must call it without waiting."""
        self.alarms.append((reason, wait))

    def fill(self, out: np.ndarray) -> None:
        k = np.arange(self.n, self.n + len(out), dtype=np.float32)
        out[:, 0] = k / 1e4
        out[:, 1] = -k / 1e4
        self.n += len(out)


# ---------------------------------------------------------------- device by name
def test_exact_then_unique_substring_then_default():
    assert find_output_device(DEVICES, HOSTAPIS, "system") == 3
    assert find_output_device(DEVICES, HOSTAPIS, "SYSTEM") == 3
    assert find_output_device(DEVICES, HOSTAPIS, "codec") == 1
    assert find_output_device(DEVICES, HOSTAPIS, "jack") == 3  # host API name matches too
    assert find_output_device(DEVICES, HOSTAPIS, "", default_index=1) == 1


def test_unknown_name_lists_the_stereo_outputs_and_the_fix():
    with pytest.raises(DeviceError) as err:
        find_output_device(DEVICES, HOSTAPIS, "Focusrite")
    msg = str(err.value)
    assert "[audio] device = 'Focusrite'" in msg
    assert "'system (JACK Audio Connection Kit)'" in msg
    assert "'USB Audio CODEC: Audio (hw:1,0) (ALSA)'" in msg
    assert "mic" not in msg and "mono out" not in msg  # inputs and mono devices are no use
    assert "plug in" in msg


def test_ambiguous_name_names_the_candidates():
    with pytest.raises(DeviceError, match="several outputs.*HDA Intel.*USB Audio CODEC"):
        find_output_device(DEVICES, HOSTAPIS, "hw:")


def test_mono_device_is_refused_even_by_exact_name():
    with pytest.raises(DeviceError, match="no stereo output"):
        find_output_device(DEVICES, HOSTAPIS, "mono out")


def test_no_default_output():
    with pytest.raises(DeviceError, match="no default stereo output"):
        find_output_device(DEVICES, HOSTAPIS, "", default_index=-1)


def test_device_plugged_in_after_start_is_found_by_a_rescan():
    sd = FakeSd(devices=DEVICES[:2])
    sd.plugged_on_rescan = [DEVICES[3]]
    out = SounddeviceOutput("system", 48000, 256, sd=sd)
    out.start(RampSource())
    assert sd.rescans == 1
    assert sd.streams[0].kw["device"] == 2
    out.stop()


# ---------------------------------------------------------------- streaming
def started(src, sd=None):
    """An output on the fake PortAudio ``system`` device, started on ``src``: (output,
    its stream, src)."""
    sd = sd or FakeSd()
    out = SounddeviceOutput("system", sd=sd)
    out.start(src)
    return out, sd.streams[0], src


def test_stream_settings_and_callback_pulls_from_the_source():
    sd = FakeSd()
    out = SounddeviceOutput("system", 48000, 128, sd=sd)
    src = RampSource()
    out.start(src)
    stream = sd.streams[0]
    kw = stream.kw
    assert (kw["device"], kw["samplerate"], kw["blocksize"]) == (3, 48000, 128)
    assert (kw["channels"], kw["dtype"]) == (2, "float32")
    played = stream.pump(3)
    k = np.arange(3 * 128, dtype=np.float32)
    np.testing.assert_array_equal(played[:, 0], k / 1e4)
    np.testing.assert_array_equal(played[:, 1], -k / 1e4)
    st = out.status()
    assert st["state"] == "running" and st["blocks"] == 3
    assert st["latency_s"] == pytest.approx(0.0107)
    assert st["device"] == "system (JACK Audio Connection Kit)"
    assert st["period_ms"]["n"] == 2 and st["fill_ms"]["n"] == 3  # timing kept per callback
    assert st["dac_lead_ms"]["p50_ms"] == pytest.approx(8.0)
    out.stop()


def test_underruns_are_counted():
    out, stream, _ = started(RampSource())
    stream.pump(5)
    stream.pump(2, underflow=True)
    stream.pump(1)
    assert out.status()["underruns"] == 2
    assert out.status()["underruns_by_cause"] == {"late_callback": 2, "slow_fill": 0}
    out.stop()


def test_an_underflow_after_a_slow_fill_is_counted_as_its_cause():
    """PortAudio flags the callback after the late one: the fill before it took longer
    than a block period (the gate) -> ``slow_fill``; a quick one -> ``late_callback``."""
    clock = FakeClock()

    class Slow(RampSource):
        slow = False

        def fill(self, out: np.ndarray) -> None:
            super().fill(out)
            if self.slow:
                clock.t += 1.5 * len(out) / 48000  # the fill takes 1.5 periods
                self.slow = False

    sd = FakeSd()
    sd.clock = clock
    out = SounddeviceOutput("system", sd=sd)
    out.clock = clock.now
    src = Slow()
    out.start(src)
    stream = sd.streams[0]
    stream.pump(3)
    src.slow = True
    stream.pump(1)
    stream.pump(1, underflow=True)  # after the slow fill
    stream.pump(2)
    stream.pump(1, underflow=True)  # after a quick one: the callback itself came late
    st = out.status()
    assert st["underruns"] == 2
    assert st["underruns_by_cause"] == {"late_callback": 1, "slow_fill": 1}
    out.close_timeout_s = 0.1  # the fake clock stands still: stop() waits out its share
    out.stop()


def test_exception_in_source_gives_silence_for_the_rest_of_the_stream():
    class Bad(RampSource):
        def fill(self, out: np.ndarray) -> None:
            super().fill(out)
            if self.n > 256:
                out[:] = 0.3  # half-written garbage, then it dies
                raise RuntimeError("effect crashed")

    out, stream, src = started(Bad())
    first = stream.pump(1)
    assert np.any(first != 0)
    rest = stream.pump(10)  # the callback itself never raises
    assert np.all(rest == 0)
    assert src.n == 512  # the failed source is not called again
    st = out.status()
    assert st["state"] == "fault" and st["callback_errors"] == 1
    assert "effect crashed" in st["error"]
    assert len(src.alarms) == 1 and "effect crashed" in src.alarms[0][0]
    assert src.alarms[0][1] is False  # never block the audio thread
    out.stop()
    assert out.status()["state"] == "fault"


@pytest.mark.parametrize("bad", [np.nan, np.inf, 1.5, -1.01])
def test_out_of_range_or_non_finite_block_is_silenced(bad):
    class Wild(RampSource):
        def fill(self, out: np.ndarray) -> None:
            super().fill(out)
            out[17, 1] = bad

    sd = FakeSd()
    out = SounddeviceOutput("system", sd=sd)
    out.start(Wild())
    played = sd.streams[0].pump(2)
    assert np.all(played == 0)
    assert out.status()["state"] == "fault"
    out.stop()


def test_stop_is_idempotent_and_silences_before_closing():
    out, stream, src = started(RampSource())
    out.stop()
    assert stream.closed and not stream.active
    assert np.all(stream.pump(2) == 0)  # a late callback after stop writes zeros
    out.stop()
    out.stop()
    st = out.status()
    assert st["state"] == "stopped" and st["error"] == ""
    assert src.alarms == []  # an ordinary stop is no alarm
    SounddeviceOutput("system", sd=FakeSd()).stop()  # never started: fine too


def test_stop_drains_the_queue_instead_of_dropping_it():
    """The queued blocks (the gate's ramp down among them) play out: ``stop()``, not
    ``abort()``, then close."""
    sd = FakeSd()
    out, stream, src = started(RampSource(), sd)
    stream.pump(3)
    out.stop()
    assert sd.calls == ["stop", "close"]
    st = out.status()
    assert st["state"] == "stopped" and st["last_stop"] == "drained" and st["error"] == ""
    assert np.all(stream.pump(1) == 0)


def test_stop_falls_back_to_abort_when_the_drain_hangs():
    sd = FakeSd()
    sd.stop_hangs = True
    out, stream, _ = started(RampSource(), sd)
    out.close_timeout_s = 0.2
    out.stop()  # returns within close_timeout_s
    sd.release_stop.set()
    assert sd.calls[:3] == ["stop", "abort", "close"]
    st = out.status()
    assert st["last_stop"] == "aborted" and st["state"] == "stopped"
    assert asd._open_streams == 0


def test_stop_lets_the_gates_ramp_down_reach_the_dac_before_stopping():
    """Stopped while the gate still ramps down: the callbacks keep pulling the ramp and
    the silence after it, and the stream is only stopped once the last block with sound
    has reached the DAC (PortAudio's ALSA stop drops the ALSA buffer, JACK's silences the
    next period: stopping earlier would cut the ramp, a step)."""

    class RampDown(RampSource):
        def __init__(self) -> None:
            super().__init__()
            self.level = 0.5
            self.handed: list[float] = []

        def fill(self, out: np.ndarray) -> None:
            k = np.arange(1, len(out) + 1)
            x = np.maximum(self.level - 0.001 * k, 0.0)
            out[:, 0] = x
            out[:, 1] = 0.0
            self.level = float(x[-1])
            self.handed.append(self.level)

    clock = FakeClock()
    sd = FakeSd()
    sd.clock = clock
    out = SounddeviceOutput("system", sd=sd)
    out.clock = clock.now
    src = RampDown()
    out.start(src)
    stream = sd.streams[0]
    stream.pump(1)
    stopper = threading.Thread(target=out.stop)
    stopper.start()
    for _ in range(200):  # PortAudio keeps calling back until the stream is stopped
        if "stop" in sd.calls:
            break
        stream.pump(1)
        stopper.join(0.002)
    stopper.join(5)
    assert not stopper.is_alive() and "abort" not in sd.calls
    assert src.level == 0.0, "the whole ramp was pulled before the stream stopped"
    silent_after = len(src.handed) - src.handed.index(0.0)
    assert silent_after >= 2, "and silence after it, until it had reached the DAC"
    assert out.status()["last_stop"] == "drained"


def test_restart_after_stop_opens_a_new_stream():
    sd = FakeSd()
    out = SounddeviceOutput("system", sd=sd)
    out.start(RampSource())
    with pytest.raises(DeviceError, match="already started"):
        out.start(RampSource())
    out.stop()
    out.start(RampSource())
    assert len(sd.streams) == 2 and out.status()["state"] == "running"
    out.stop()


def test_vanished_device_is_reported_and_silenced():
    out, stream, src = started(RampSource())
    stream.pump(2)
    stream.vanish()
    st = out.status()
    assert st["state"] == "lost"
    assert [wait for _, wait in src.alarms] == [False]  # the gate is told once
    assert "unplugged" in st["error"]
    assert np.all(stream.pump(1) == 0)
    out.stop()
    assert out.status()["state"] == "lost"


def test_stop_returns_even_when_portaudio_hangs_closing_a_dead_device():
    """PortAudio blocks forever closing a stream whose JACK server died: stop() must not."""
    sd = FakeSd()
    out = SounddeviceOutput("system", sd=sd)
    out.close_timeout_s = 0.05
    src = RampSource()
    out.start(src)
    stream = sd.streams[0]
    stream.vanish()
    sd.close_hangs = True
    out.stop()  # returns after close_timeout_s
    st = out.status()
    assert st["state"] == "lost" and "closing the stream hung" in st["error"]
    assert asd._open_streams == 1  # PortAudio is not rescanned under a hung stream
    sd.plugged_on_rescan = [DEVICES[3]]
    with pytest.raises(DeviceError):
        asd.locate(sd, "no such device")
    assert sd.rescans == 0
    out.stop()  # still fine
    sd.release_close.set()
    asd._open_streams = 0  # (the hung stream of this fake is gone now)


def test_device_that_cannot_start_gives_a_clear_error():
    sd = FakeSd()
    sd.fail_start = True
    out = SounddeviceOutput("system", sd=sd)
    with pytest.raises(DeviceError, match="cannot start the stream.*Device unavailable"):
        out.start(RampSource())
    assert out.status()["state"] == "lost"
    assert sd.streams[0].closed
    assert asd._open_streams == 0


def test_unsupported_sample_rate_names_the_profile_keys():
    out = SounddeviceOutput("system", sample_rate_hz=12345, sd=FakeSd())
    with pytest.raises(DeviceError, match=r"12345 Hz.*\[audio\] sample_rate_hz"):
        out.start(RampSource())


# ---------------------------------------------------------------- factory and probe
def test_factory_reads_the_profile(stub_profile):
    p = stub_profile(
        audio__device="USB Audio CODEC",
        audio__sample_rate_hz=44100,
        audio__block_size=512,
        sounddevice__latency_s=0.02,
    )
    out = asd.from_profile(p)
    assert (out.device, out.sample_rate_hz, out.block_size, out.latency_s) == (
        "USB Audio CODEC",
        44100,
        512,
        0.02,
    )


def test_probe_ok_and_missing(stub_profile):
    ok = asd.probe(stub_profile(audio__device="codec"), sd=FakeSd())
    assert ok.state == "ok" and "USB Audio CODEC" in ok.why
    gone = asd.probe(stub_profile(audio__device="Focusrite"), sd=FakeSd())
    assert gone.state == "missing"
    assert "system (JACK Audio Connection Kit)" in gone.why
    assert "plug in" in gone.fix


def test_probe_without_portaudio_says_what_to_install(stub_profile, monkeypatch):
    def no_portaudio() -> Any:
        raise DeviceError("sounddevice: PortAudio not found (PortAudio library not found)")

    monkeypatch.setattr(asd, "load_sounddevice", no_portaudio)
    st = asd.probe(stub_profile())
    assert st.state == "missing"
    assert st.fix == "install PortAudio: apt-get install libportaudio2"
