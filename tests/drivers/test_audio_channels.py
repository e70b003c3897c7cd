"""The sounddevice driver opens as many channels as ``[audio] channels`` names, and says
which device cannot (a fake ``sounddevice`` module: no PortAudio needed)."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from plugins.drivers import audio_sounddevice as asd
from plugins.drivers.errors import DeviceError

HOSTAPIS = [{"name": "ALSA"}]
DEVICES = [
    {"name": "USB Audio CODEC: Audio (hw:1,0)", "hostapi": 0, "max_output_channels": 2},
    {"name": "Scarlett 18i8: USB Audio (hw:2,0)", "hostapi": 0, "max_output_channels": 8},
]
FIVE = ["PA", "PB", "PC", "PD", "screen"]


class Sd:
    """Enough of ``sounddevice`` for opening a stream and running its callback once."""

    def __init__(self) -> None:
        self.default = SimpleNamespace(device=[-1, 1])
        self.kw: dict[str, Any] = {}

    def query_devices(self):
        return DEVICES

    def query_hostapis(self):
        return HOSTAPIS

    def _terminate(self):
        pass

    def _initialize(self):
        pass

    def OutputStream(self, **kw):  # noqa: N802 (mirrors sounddevice)
        self.kw = kw
        return SimpleNamespace(
            start=lambda: None,
            abort=lambda ignore_errors=True: None,
            close=lambda ignore_errors=True: None,
            active=True,
            latency=0.01,
        )


class Columns:
    """A source writing its column index + 1 (scaled) into every column."""

    idle = False

    def fill(self, out: np.ndarray) -> None:
        out[:] = (np.arange(out.shape[1]) + 1) / 10


def test_a_five_channel_profile_opens_five_channels(stub_profile):
    sd = Sd()
    prof = stub_profile(audio__device="Scarlett", audio__channels=FIVE)
    drv = asd.from_profile(prof)
    drv._sd = sd
    drv.start(Columns())
    assert sd.kw["channels"] == 5 and drv.status()["channels"] == 5
    out = np.zeros((64, 5), np.float32)
    sd.kw["callback"](out, 64, SimpleNamespace(), SimpleNamespace(output_underflow=False))
    assert np.allclose(out[0], [0.1, 0.2, 0.3, 0.4, 0.5])
    drv.stop()
    st = asd.probe(prof, sd=sd)
    assert st.state == "ok" and "5 channels" in st.why


def test_a_stereo_card_for_five_channels_is_named_with_its_count(stub_profile):
    prof = stub_profile(audio__device="CODEC", audio__channels=FIVE)
    st = asd.probe(prof, sd=Sd())
    assert st.state == "missing"
    assert "has 2 output channels" in st.why and "[audio] channels names 5" in st.why
    with pytest.raises(DeviceError, match="has 2 output channels"):
        asd.find_output_device(DEVICES, HOSTAPIS, "codec", channels=5)
    # the default output must have the channels too
    assert asd.find_output_device(DEVICES, HOSTAPIS, "", default_index=1, channels=5) == 1
    with pytest.raises(DeviceError, match="no default output with 5 channels"):
        asd.find_output_device(DEVICES, HOSTAPIS, "", default_index=0, channels=5)


def test_a_bus_profile_still_opens_two(stub_profile):
    sd = Sd()
    drv = asd.from_profile(stub_profile(audio__device="codec"))
    drv._sd = sd
    drv.start(Columns())
    assert sd.kw["channels"] == 2
    drv.stop()
