"""The hardware drivers by registration kind, and their registration."""

from __future__ import annotations

import importlib
from typing import Any

#: Registration kind -> (name, driver module, description). Each driver module has
#: ``from_profile(profile)`` (the factory) and ``probe(profile)`` (for ``haptable doctor``).
DRIVERS: dict[str, tuple[tuple[str, str, str], ...]] = {
    "audio_output": (
        (
            "sounddevice",
            "audio_sounddevice",
            "sound card through PortAudio (sounddevice), 2 channels float32",
        ),
    ),
    "relay_board": (
        (
            "yoctopuce",
            "relay_yocto",
            "Yocto-MaxiCoupler, 8 relays, through the official yoctopuce library",
        ),
        ("hid", "relay_hid", "generic 0x16c0:0x05df USB HID relay board through pyusb"),
    ),
    "camera": (
        (
            "opencv",
            "camera_opencv",
            "V4L2/OpenCV camera (PS3 Eye), 8-bit grayscale, reconnects after unplug",
        ),
    ),
}


def register_drivers(register: Any, kind: str) -> None:
    """Register every driver of ``kind`` (its module imported here; the hardware library
    it wraps loads when a device opens)."""
    for name, module, description in DRIVERS[kind]:
        driver = importlib.import_module(f"{__package__}.{module}")
        extra = {"devices": driver.list_devices} if kind == "audio_output" else {}
        register(name, driver.from_profile, description=description, probe=driver.probe, **extra)
