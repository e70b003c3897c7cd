"""Real hardware drivers: sound card (PortAudio), relay boards (Yoctopuce, HID), camera (OpenCV).

Each hardware library (sounddevice, yoctopuce, pyusb, cv2) is imported only inside the
factory or probe that needs it, so importing this plugin costs nothing on the twin.
"""

from __future__ import annotations

from typing import Any

from console.hookspecs import hookimpl
from console.schema import Field


@hookimpl
def haptable_profile_sections(register: Any) -> None:
    register(
        "sounddevice",
        {
            "device": Field(
                "str",
                "",
                help="output device name or a unique part of it (empty: system default); "
                "`haptable doctor` lists the choices",
            ),
            "latency_s": Field(
                "float", 0.0, min=0.0, max=1.0, help="suggested output latency; 0 = lowest"
            ),
        },
        help="the sound card of audio driver 'sounddevice' (left: piezo, right: screen)",
    )
    register(
        "yoctopuce",
        {
            "hub_url": Field(
                "str",
                "usb",
                help="'usb' (direct, one process at a time) or a VirtualHub/YoctoHub URL "
                "such as '127.0.0.1' to share the board between processes",
            ),
            "serial": Field(
                "str", "", help="module serial, e.g. 'MAXICPL1-12345'; empty: the first found"
            ),
        },
        help="the Yocto-MaxiCoupler of relay driver 'yoctopuce'",
    )
    register(
        "usbrelay",
        {
            "serial": Field(
                "str", "", help="5-character board serial; empty: the only board plugged in"
            ),
        },
        help="the 0x16c0:0x05df HID relay board of relay driver 'hid'",
    )


@hookimpl
def haptable_register_audio_outputs(register: Any) -> None:
    from plugins.drivers import audio_sounddevice

    register(
        "sounddevice",
        audio_sounddevice.from_profile,
        description="sound card through PortAudio (sounddevice), 2 channels float32",
        probe=audio_sounddevice.probe,
    )
