"""Real hardware drivers: sound card (PortAudio), relay boards (Yoctopuce, HID), camera (OpenCV).

Each hardware library (sounddevice, yoctopuce, pyusb, cv2) is imported only inside the
factory or probe that needs it, so importing this plugin costs nothing on the twin.
"""

from __future__ import annotations

import importlib
from typing import Any

from console.plugin_api import Field, hookimpl


@hookimpl
def haptable_profile_sections(register: Any) -> None:
    # The device keys live in the core sections: [audio] device, [relays] serial / url,
    # [camera] device width_px height_px fps exposure gain.
    register(
        "sounddevice",
        {
            "latency_s": Field(
                "float",
                0.0,
                min=0.0,
                max=1.0,
                help="suggested output latency for audio driver 'sounddevice'; 0 = lowest",
            ),
        },
        help="PortAudio settings of audio driver 'sounddevice'",
    )


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


def _register(register: Any, kind: str) -> None:
    for name, module, description in DRIVERS[kind]:
        driver = importlib.import_module(f"{__name__}.{module}")
        extra = {"devices": driver.list_devices} if kind == "audio_output" else {}
        register(name, driver.from_profile, description=description, probe=driver.probe, **extra)


@hookimpl
def haptable_register_audio_outputs(register: Any) -> None:
    _register(register, "audio_output")


@hookimpl
def haptable_register_relay_boards(register: Any) -> None:
    _register(register, "relay_board")


@hookimpl
def haptable_register_cameras(register: Any) -> None:
    _register(register, "camera")


@hookimpl
def haptable_register_benchmarks(register: Any) -> None:
    from plugins.drivers import bench_audio

    register(
        "audio-output",
        bench_audio.run,
        help="callback period, gate fill time, underruns and latency of [audio] driver (silent)",
    )
