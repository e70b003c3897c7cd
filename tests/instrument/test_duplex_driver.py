"""The sounddevice driver opens its inputs beside its outputs when the profile names them."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from console.core.audio_inputs import InputSpec
from plugins.drivers.audio_sounddevice import SounddeviceOutput


class _Stream:
    def __init__(self, **kw: Any) -> None:
        self.kw, self.active, self.latency = kw, False, 0.01

    def start(self) -> None:
        self.active = True

    def stop(self, ignore_errors: bool = True) -> None:
        self.active = False

    def abort(self, ignore_errors: bool = True) -> None:
        self.active = False

    def close(self, ignore_errors: bool = True) -> None:
        pass


class _Sd:
    """A duplex card: 2 inputs, 2 outputs (what sounddevice's API offers)."""

    def __init__(self) -> None:
        self.opened: list[tuple[str, dict]] = []
        self.default = SimpleNamespace(device=[0, 0])

    def query_devices(self) -> list[dict]:
        return [{"name": "card", "hostapi": 0, "max_output_channels": 2, "max_input_channels": 2}]

    def query_hostapis(self) -> list[dict]:
        return [{"name": "ALSA"}]

    def OutputStream(self, **kw: Any) -> _Stream:  # noqa: N802 (mirrors sounddevice)
        self.opened.append(("output", kw))
        return _Stream(**kw)

    def Stream(self, **kw: Any) -> _Stream:  # noqa: N802 (mirrors sounddevice)
        self.opened.append(("duplex", kw))
        return _Stream(**kw)


class _Gate:
    idle = False

    def __init__(self) -> None:
        self.clock = 0

    def fill(self, out: np.ndarray) -> None:
        out[:, 0] = (self.clock + np.arange(out.shape[0])) * 1e-4  # a ramp: its clock
        out[:, 1:] = 0.0
        self.clock += out.shape[0]


def test_inputs_are_kept_by_the_clock_of_the_outputs_filled_beside_them():
    sd = _Sd()
    acc = InputSpec("accel", 2, "accelerometer", 10.2)
    drv = SounddeviceOutput("card", 48000, 64, sd=sd, inputs=(acc,))
    gate = _Gate()
    drv.start(gate)
    kind, kw = sd.opened[-1]
    assert kind == "duplex" and kw["channels"] == (2, 2)
    for _ in range(3):  # PortAudio's callback: input 2 carries what output 1 played
        out = np.zeros((64, 2), np.float32)
        clock = gate.clock
        indata = np.zeros((64, 2), np.float32)
        indata[:, 1] = (clock + np.arange(64)) * 1e-4
        kw["callback"](indata, out, 64, SimpleNamespace(), SimpleNamespace())
    assert drv.input_clock() == 192
    got = drv.read_inputs(10, 150)[:, 0]
    assert np.allclose(got, np.arange(10, 150) * 1e-4)
    drv.stop()


def test_without_inputs_the_driver_opens_an_output_stream_only():
    sd = _Sd()
    drv = SounddeviceOutput("card", 48000, 64, sd=sd)
    drv.start(_Gate())
    assert sd.opened[-1][0] == "output"
    assert drv.read_inputs(0, 10).shape == (10, 0)
    drv.stop()
