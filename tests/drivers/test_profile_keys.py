"""Every profile key the drivers read exists in the real profiles (a typo would read None)."""

from __future__ import annotations

import pytest

from plugins.drivers import audio_sounddevice, camera_opencv, relay_hid, relay_yocto
from plugins.drivers.errors import DeviceError


class Strict:
    """A real profile whose ``get`` fails on a key the schema does not have."""

    def __init__(self, profile) -> None:
        self.profile = profile
        self.read: set[str] = set()

    def get(self, key: str):
        value = self.profile.get(key)
        if value is None:
            raise KeyError(f"profile has no key {key!r}")
        self.read.add(key)
        return value


def missing(what: str):
    def load():
        raise DeviceError(f"{what} not importable (test)")

    return load


class Recorder:
    def __init__(self, *args, **kwargs) -> None:
        self.kwargs = kwargs


@pytest.mark.parametrize("name", ["sim", "haptable-lab"])
def test_factories_and_probes_read_existing_keys(name, plugins, monkeypatch):
    from console.config.profile import load_profile

    prof = Strict(load_profile(name, plugins))
    for module, cls in (
        (audio_sounddevice, "SounddeviceOutput"),
        (relay_hid, "HidRelayBoard"),
        (relay_yocto, "YoctoRelayBoard"),
        (camera_opencv, "OpenCVCamera"),
    ):
        monkeypatch.setattr(module, cls, Recorder)
        made = module.from_profile(prof)
        assert all(v is not None for v in made.kwargs.values())
    # no hardware library in reach: each probe must still answer from the profile
    monkeypatch.setattr(relay_yocto, "load_yocto", missing("yoctopuce"))
    monkeypatch.setattr(relay_hid, "load_usb", missing("pyusb"))
    monkeypatch.setattr(audio_sounddevice, "load_sounddevice", missing("PortAudio"))
    for module in (audio_sounddevice, relay_hid, relay_yocto, camera_opencv):
        st = module.probe(prof)
        assert st.state in ("ok", "missing", "error")
    assert {"audio.device", "relays.serial", "relays.url", "camera.device"} <= prof.read
    assert "sounddevice.latency_s" in prof.read  # this plugin's own section has its default


def test_driver_names_are_registered(plugins):
    assert "sounddevice" in plugins.of("audio_output")
    assert {"yoctopuce", "hid"} <= set(plugins.of("relay_board"))
    assert "opencv" in plugins.of("camera")
    for kind in ("audio_output", "relay_board", "camera"):
        for reg in plugins.of(kind).values():
            if reg.plugin == "drivers":
                assert reg.probe is not None and reg.description
