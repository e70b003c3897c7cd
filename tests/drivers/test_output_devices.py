"""What the Devices screen lists of the sounddevice driver: every PortAudio output with its
host API, channels and default latencies (a fake PortAudio, then a real JACK server)."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from plugins.drivers.audio_sounddevice import find_output_device, list_devices

HOSTAPIS = [{"name": "ALSA"}, {"name": "JACK Audio Connection Kit"}]
DEVICES = [
    {"name": "HDA Intel PCH (hw:0,0)", "hostapi": 0, "max_output_channels": 2,
     "default_low_output_latency": 0.0087, "default_high_output_latency": 0.034},
    {"name": "USB mic", "hostapi": 0, "max_output_channels": 0},
    {"name": "system", "hostapi": 1, "max_output_channels": 8,
     "default_low_output_latency": 0.0053, "default_high_output_latency": 0.0053},
    {"name": "mono out", "hostapi": 0, "max_output_channels": 1,
     "default_low_output_latency": 0.01, "default_high_output_latency": 0.04},
]  # fmt: skip


class FakeSd:
    def __init__(self) -> None:
        self.default = SimpleNamespace(device=[-1, 2])
        self.rescans = 0

    def query_devices(self):
        return DEVICES

    def query_hostapis(self):
        return HOSTAPIS

    def _terminate(self):
        self.rescans += 1

    def _initialize(self):
        pass


def test_every_output_is_listed_with_host_api_channels_and_latency():
    sd = FakeSd()
    found = list_devices(None, sd=sd)
    assert sd.rescans == 1  # freshly plugged cards show up
    assert [d.name for d in found] == [
        "HDA Intel PCH (hw:0,0) (ALSA)",
        "system (JACK Audio Connection Kit)",
        "mono out (ALSA)",
    ]  # the input-only device is not an output
    hda, jack, mono = found
    assert (hda.host_api, hda.output_channels) == ("ALSA", 2)
    assert (hda.low_latency_s, hda.high_latency_s) == (0.0087, 0.034)
    assert jack.default and not hda.default
    assert hda.note == "" and mono.note == "1 output channel: needs 2"
    # the name saved to [audio] device picks exactly that device again
    for dev, index in ((hda, 0), (jack, 2)):
        assert find_output_device(DEVICES, HOSTAPIS, dev.name) == index


@pytest.mark.hardware
@pytest.mark.xdist_group("jack")
def test_a_real_jack_server_is_listed_and_its_name_opens_it(jack_server):
    import sounddevice as sd

    found = list_devices(None)
    jack = [d for d in found if "JACK" in d.host_api and d.output_channels >= 2]
    assert jack, [d.name for d in found]
    dev = jack[0]
    assert dev.note == "" and dev.low_latency_s > 0
    index = find_output_device(list(sd.query_devices()), list(sd.query_hostapis()), dev.name)
    assert sd.query_devices(index)["name"] in dev.name
